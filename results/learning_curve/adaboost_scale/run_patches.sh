#!/usr/bin/env bash
# The paper's patch protocol (and x1 frames) for AdaBoost with the energy floor, 100 seeds, halmstad_v2; the trained
# detectors of run_floor.sh are read back from the cell cache.
# usage (repository root): results/learning_curve/adaboost_scale/run_patches.sh TAG "SEEDS" F
set -euo pipefail
tag=$1; seeds=$2; floor=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors adaboost --seed-counts 100 --no-scale-check --training-seeds $seeds --threads 1 \
  --ada-energy-floor "$floor" "$@" \
  --out "results/learning_curve/adaboost_scale/$tag" > "results/learning_curve/adaboost_scale/$tag.log" 2>&1
