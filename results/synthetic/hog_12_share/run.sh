#!/usr/bin/env bash
# Issue 16's 12-seed target for HOG (drones): 12 real seeds (each training seed's own 12-seed set) alone and + 20x
# synthetic from a d_HOG fit of that 12-seed set (made by the runner), protocol halmstad_v2, the library's defaults
# (ensemble box map), plus the runner options given (e.g. --synthetic-share 0.25).
# usage (repository root): results/synthetic/hog_12_share/run.sh SPLIT "SEEDS" OUT [runner options...]
#   run.sh test "0 2 4" results/synthetic/hog_12_share/count_a        (writes OUT/ and OUT.log)
set -euo pipefail
split=$1; seeds=$2; out=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors hog --seed-counts 12 --synthetic-ratios 20 --fit-distance hog \
  --no-scale-check --no-patches --eval-split "$split" --training-seeds $seeds --threads 1 "$@" \
  --out "$out" > "$out.log" 2>&1
