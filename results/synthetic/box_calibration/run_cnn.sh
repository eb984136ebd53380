#!/usr/bin/env bash
# The CNN's box calibration on more training seeds (stop 74): real only, 100 seeds, the CNN's defaults, scored with
# the calibration (the family default, 20) on SPLIT; the same stored detectors read back with --box-calibration 0.
# usage (repository root): results/synthetic/box_calibration/run_cnn.sh SPLIT "SEEDS" OUT [runner options...]
set -euo pipefail
split=$1; seeds=$2; out=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors cnn --seed-counts 100 --synthetic-ratios --no-scale-check --no-patches --eval-split "$split" \
  --training-seeds $seeds --threads 1 "$@" --out "$out" > "$out.log" 2>&1
