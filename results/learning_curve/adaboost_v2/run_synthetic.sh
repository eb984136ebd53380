#!/usr/bin/env bash
# Issue 15/16: AdaBoost under protocol halmstad_v2 with its defaults (ensemble box map), 100 real seeds, real only
# and + 20x synthetic from each training seed's own d_HOG fit (the fits the HOG and CNN tables use).
# usage (repository root): results/learning_curve/adaboost_v2/run_synthetic.sh TAG "SEEDS" [runner options...]
set -euo pipefail
tag=$1; seeds=$2; shift 2
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors adaboost --seed-counts 100 --synthetic-ratios 20 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' \
  --no-scale-check --no-patches --training-seeds $seeds --threads 1 "$@" \
  --out "results/learning_curve/adaboost_v2/$tag" > "results/learning_curve/adaboost_v2/$tag.log" 2>&1
