#!/usr/bin/env bash
# Issue 15: AdaBoost's x2 scale check with scale-jittered hard-negative mining (--mining-frame-scale 0.75 2),
# protocol halmstad_v2, 100 seeds, x1 / x2 / x0.75 scored. Trains the detectors (cell cache). Run before the energy
# floor became AdaBoost's default: --ada-energy-floor 0 is the training it measured.
# usage (repository root): results/learning_curve/adaboost_scale/run.sh TAG "SEEDS" [runner options]
set -euo pipefail
tag=$1; seeds=$2; shift 2
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors adaboost --seed-counts 100 --no-patches --training-seeds $seeds --threads 1 \
  --mining-frame-scale 0.75 2 --ada-energy-floor 0 "$@" \
  --out "results/learning_curve/adaboost_scale/$tag" > "results/learning_curve/adaboost_scale/$tag.log" 2>&1
