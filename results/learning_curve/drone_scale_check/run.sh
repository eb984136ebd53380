#!/bin/bash
# issue 15: the x2 / x0.75 scale check of the protocol (test frames resized, the detectors unchanged) for HOG and the
# CNN at 100 real seeds, 3 training seeds each (the learning curve's drone_v6 cells were run with --no-scale-check; the
# scored scales are part of a cell's key, so these cells are trained again: same seeds, same code).
# DETECTOR=hog|cnn
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner learning-curve --class drone --detectors ${DETECTOR:-hog} \
  --seed-counts 100 --training-seeds 0 1 2 --out results/learning_curve/drone_scale_check/${DETECTOR:-hog}
