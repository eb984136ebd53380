#!/usr/bin/env bash
# Issue 16, item 5: the paper's Fig. 10 (fitted capture parameters vs drawn uniformly between the fitted extremes) under
# protocol halmstad_v2, HOG, 100 real seeds + 20x synthetic, 5 training seeds, the same d_HOG fits and defaults as
# ../drone_v2_ensemble/ (whose real-only and fitted cells are read back). usage (repository root):
#   results/synthetic/drone_v2_capture/run.sh [runner options, e.g. --read-only]
set -euo pipefail
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
  --synthetic-ratios 20 --capture-sampling seed uniform --fit-distance hog --no-scale-check --no-patches --threads 1 \
  --training-seeds 0 1 2 3 4 --seed-counts 100 "$@" --out results/synthetic/drone_v2_capture/hog_100 \
  > results/synthetic/drone_v2_capture/hog_100.log 2>&1
