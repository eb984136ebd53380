#!/usr/bin/env bash
# Issue 15: AdaBoost's x2 / x0.75 scale check under protocol halmstad_v2 (default ensemble box map), 100 seeds; the
# trained detectors of run.sh / run_synthetic.sh are read back from the cell cache.
# usage (repository root): results/learning_curve/adaboost_v2/run_scale.sh TAG "SEEDS"
# --ada-energy-floor 0: made before AdaBoost's energy floor became its default (stop 49, ../adaboost_scale/README.md).
set -euo pipefail
tag=$1; seeds=$2; shift 2
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors adaboost --seed-counts 100 --no-patches --training-seeds $seeds --threads 1 --ada-energy-floor 0 "$@" \
  --out "results/learning_curve/adaboost_v2/$tag" > "results/learning_curve/adaboost_v2/$tag.log" 2>&1
