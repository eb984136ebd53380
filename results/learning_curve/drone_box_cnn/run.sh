#!/bin/bash
# issue 15: the box regressor's model on the protocol with its x2 / x0.75 scale check, 100 real seeds, 3 training
# seeds. DETECTOR=hog|cnn, BOX=cnn (the default, TrainOptions.box_model) | ensemble | ridge. WORK= the cell cache /
# ingest folder (default data/runs).
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
BOX=${BOX:-cnn}
OUT=results/learning_curve/drone_box_cnn/${DETECTOR:-hog}$([ "$BOX" = cnn ] || echo "_$BOX")
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner learning-curve --class drone --detectors ${DETECTOR:-hog} \
  --seed-counts 100 --training-seeds 0 1 2 --box-model $BOX --work ${WORK:-data/runs} --out $OUT
