#!/bin/bash
# issue 15: all training frames (every 3rd labelled frame) with the CNN box regressor, x1 only (--no-scale-check),
# 3 training seeds; then combine.py all pairs them with the 100-seed cells of run.sh. DETECTOR=hog|cnn.
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner learning-curve --class drone --detectors ${DETECTOR:-hog} \
  --seed-counts --all-frames --no-scale-check --training-seeds 0 1 2 --work ${WORK:-data/runs} \
  --out results/learning_curve/drone_box_cnn/${DETECTOR:-hog}_all_cells
python results/learning_curve/drone_box_cnn/combine.py all ${DETECTOR:-hog} ${WORK:-data/runs}
