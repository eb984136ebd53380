#!/usr/bin/env bash
# Issue 16, item 5: the paper's Fig. 11 (synthetic-to-real ratio) under protocol halmstad_v2, HOG, 100 real seeds,
# 5 training seeds, the same d_HOG fits and defaults as ../drone_v2_ensemble/ (whose 20x cells are read back).
# usage (repository root): results/synthetic/drone_v2_ratio/run.sh
set -euo pipefail
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
  --synthetic-ratios 5 20 50 --fit-distance hog --no-scale-check --no-patches --threads 1 --training-seeds 0 1 2 3 4 \
  --seed-counts 100 --out results/synthetic/drone_v2_ratio/hog_100 > results/synthetic/drone_v2_ratio/hog_100.log 2>&1
