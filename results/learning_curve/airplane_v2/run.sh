#!/usr/bin/env bash
# Issue 15, item 7 on the second class: the airplane learning curve under protocol halmstad_v2 (default box map),
# real data only, the pyramid extended to 0.26 as ../../synthetic/airplane_v2/ (whose 12- and 100-seed cells it shares).
# usage (repository root): results/learning_curve/airplane_v2/run.sh DETECTOR TAG "SEEDS" [runner options...]
#   run.sh hog hog "0 1 2" --seed-counts 12 100 --all-frames
set -euo pipefail
det=$1; tag=$2; seeds=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class airplane \
  --detectors "$det" --scales 1.25 1.0 0.8 0.64 0.51 0.41 0.33 0.26 --no-scale-check --no-patches \
  --training-seeds $seeds --threads 1 "$@" \
  --out "results/learning_curve/airplane_v2/$tag" > "results/learning_curve/airplane_v2/$tag.log" 2>&1
