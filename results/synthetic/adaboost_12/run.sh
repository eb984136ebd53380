#!/usr/bin/env bash
# Issue 16's 12-seed target for AdaBoost (drones): 12 real seeds (each training seed's own 12-seed set) alone and
# + 20x synthetic from a d_HOG fit of that 12-seed set (made by the runner), protocol halmstad_v2, every fitted effect
# (--effects-off none, as the 100-seed AdaBoost row), Dynamic-TrAdaBoost (--ada-transfer), AdaBoost's defaults.
# usage (repository root): results/synthetic/adaboost_12/run.sh SPLIT "SEEDS" OUT [runner options...]
#   run.sh test "0" results/synthetic/adaboost_12/seed0        (writes OUT/ and OUT.log)
#   ADA_TRANSFER=0 run.sh ...   plain AdaBoost: the synthetic positives without the transfer rule (stop 59)
# --ada-cascade all: AdaBoost's soft cascade from every training positive, as these cells were run before the
# real-positive cascade became the default (stop 60); the last value given wins.
# --synthetic-share count: every positive weighs the same, as these cells were run before AdaBoost's default share
# of 0.25 (stop 61); --synthetic-share 0.25 (or any other value given after it) wins.
set -euo pipefail
split=$1; seeds=$2; out=$3; shift 3
transfer=(--ada-transfer); if [ "${ADA_TRANSFER:-1}" = 0 ]; then transfer=(); fi
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors adaboost --seed-counts 12 --synthetic-ratios 20 --fit-distance hog "${transfer[@]}" \
  --no-scale-check --no-patches --eval-split "$split" --training-seeds $seeds --threads 1 --effects-off none \
  --ada-cascade all --synthetic-share count "$@" \
  --out "$out" > "$out.log" 2>&1
