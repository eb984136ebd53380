#!/usr/bin/env bash
# Issue 15's remaining checks under protocol halmstad_v2 with the defaults (ensemble box map), 100 real seeds, the
# trained detectors read back from the cell cache: the x2 / x0.75 scale check and the paper's patch protocol.
# usage (repository root): results/learning_curve/v2_checks/run.sh DETECTOR TAG "SEEDS" [runner options...]
#   run.sh cnn cnn_100 "0 1 2 3 4"                       (scale check and patches)
#   run.sh hog hog_100_patches "0 1 2 3 4" --no-scale-check
set -euo pipefail
det=$1; tag=$2; seeds=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors "$det" --seed-counts 100 --training-seeds $seeds --threads 1 "$@" \
  --out "results/learning_curve/v2_checks/$tag" > "results/learning_curve/v2_checks/$tag.log" 2>&1
