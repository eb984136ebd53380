#!/usr/bin/env bash
# Issue 15 under protocol halmstad_v2 (frames without a labelled box not scored), test split, ridge box map.
# usage (from the repository root): results/learning_curve/drone_v2/run.sh TAG DETECTOR [runner options...]
#   e.g. run.sh hog_100 hog --seed-counts 100                      (with the x2 / x0.75 scale check)
#        run.sh hog_all hog --seed-counts --all-frames --no-scale-check
set -euo pipefail
tag=$1; det=$2; shift 2
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors "$det" "$@" --box-model ridge --no-patches --training-seeds 0 1 2 --threads 1 \
  --out "results/learning_curve/drone_v2/$tag"
