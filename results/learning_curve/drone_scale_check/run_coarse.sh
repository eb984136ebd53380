#!/bin/bash
# issue 15: the x2 / x0.75 scale check with a pyramid that reaches larger objects: the default levels
# (1.25 ... 0.41: objects of ~22-68 px in the 40-px window) plus 0.33 0.26 0.21 0.17 (up to ~165 px), for mining,
# validation and scoring alike (--scales is part of a cell's key). Paired against run.sh's cells (default pyramid).
# DETECTOR=hog|cnn
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner learning-curve --class drone --detectors ${DETECTOR:-hog} \
  --seed-counts 100 --training-seeds ${SEEDS:-0 1 2} --scales 1.25 1.0 0.8 0.64 0.51 0.41 0.33 0.26 0.21 0.17 \
  --out results/learning_curve/drone_scale_check/${DETECTOR:-hog}_coarse
