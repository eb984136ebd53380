#!/usr/bin/env bash
# Issue 16, item 5: the paper's Fig. 9 (each fitted effect left out of the synthetic images) under protocol
# halmstad_v2, HOG, 100 real seeds + 20x synthetic, the same d_HOG fits and defaults as ../drone_v2_ensemble/ (whose
# real-only and all-effects cells are read back). usage (repository root):
#   results/synthetic/drone_v2_effects_off/run.sh "SEEDS" [runner options, e.g. --read-only]
set -euo pipefail
seeds=$1; shift
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
  --synthetic-ratios 20 --effects-off none boundary_blur motion_blur object_noise material --fit-distance hog \
  --no-scale-check --no-patches --threads 1 --training-seeds $seeds --seed-counts 100 "$@" \
  --out results/synthetic/drone_v2_effects_off/hog_100 >> results/synthetic/drone_v2_effects_off/hog_100.log 2>&1
