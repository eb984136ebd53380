#!/usr/bin/env bash
# Issue 15: AdaBoost under protocol halmstad_v2 with its defaults (ensemble box map, mining rounds kept by
# validation AP), one training seed at a time (a cell is about an hour on one core).
# usage (repository root): results/learning_curve/adaboost_v2/run.sh TAG "SEEDS" [runner options...]
#   run.sh ada_100_seed0 "0" --seed-counts 100
# --ada-energy-floor 0: these runs were made before AdaBoost's energy floor became its default (stop 49,
# ../adaboost_scale/README.md); the option keeps them reproducible.
set -euo pipefail
tag=$1; seeds=$2; shift 2
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors adaboost "$@" --no-patches --no-scale-check --training-seeds $seeds --threads 1 --ada-energy-floor 0 \
  --out "results/learning_curve/adaboost_v2/$tag"
