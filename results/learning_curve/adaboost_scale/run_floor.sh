#!/usr/bin/env bash
# Issue 15: AdaBoost's x2 scale check with an energy floor in the stumps' normalisation (--ada-energy-floor F, in
# units of the training negatives' gradient level), protocol halmstad_v2, 100 seeds, x1 / x2 / x0.75 scored.
# usage (repository root): results/learning_curve/adaboost_scale/run_floor.sh TAG "SEEDS" F [runner options]
set -euo pipefail
tag=$1; seeds=$2; floor=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors adaboost --seed-counts 100 --no-patches --training-seeds $seeds --threads 1 \
  --ada-energy-floor "$floor" "$@" \
  --out "results/learning_curve/adaboost_scale/$tag" > "results/learning_curve/adaboost_scale/$tag.log" 2>&1
