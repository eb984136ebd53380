#!/usr/bin/env bash
# Issue 15's first target for AdaBoost with the energy floor: 100 seeds and all training frames (every 3rd labelled
# frame), protocol halmstad_v2, x1 only, no patches (as ../adaboost_v2/run.sh).
# usage (repository root): results/learning_curve/adaboost_scale/run_all.sh TAG "SEEDS" F [runner options]
set -euo pipefail
tag=$1; seeds=$2; floor=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors adaboost --seed-counts 100 --all-frames --no-patches --no-scale-check --training-seeds $seeds \
  --threads 1 --ada-energy-floor "$floor" "$@" \
  --out "results/learning_curve/adaboost_scale/$tag" > "results/learning_curve/adaboost_scale/$tag.log" 2>&1
