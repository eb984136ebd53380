#!/usr/bin/env bash
# Issue 15: HOG under protocol halmstad_v2 (ridge box map, as ../drone_v2/) after k-means restarts
# (TrainOptions.hog_kmeans_restarts = 10), training seeds 0-4.
# usage (repository root): results/learning_curve/mining_collapse/run.sh TAG [runner options...]
#   run.sh hog_all --seed-counts --all-frames --no-scale-check
#   run.sh hog_100 --seed-counts 100
set -euo pipefail
tag=$1; shift
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors hog "$@" --box-model ridge --no-patches --training-seeds 0 1 2 3 4 --threads 1 \
  --out "results/learning_curve/mining_collapse/$tag"
