#!/usr/bin/env bash
# Issue 16, the framing factor for the CNN: 100 real seeds + 20x synthetic (d_HOG fits of each training seed's
# 100-seed set) with the synthetic objects framed at the fitted renders' median box size (--object-box fit),
# protocol halmstad_v2, defaults (ensemble box map; the CNN fine-tuned on the real seeds afterwards).
# usage (repository root): results/synthetic/cnn_object_box/run.sh DETECTOR TAG SPLIT "SEEDS" [runner options...]
#   run.sh cnn cnn_val val "0 1 2" --object-box fit
set -euo pipefail
det=$1; tag=$2; split=$3; seeds=$4; shift 4
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors "$det" --seed-counts 100 --synthetic-ratios 20 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' \
  --no-scale-check --no-patches --eval-split "$split" --training-seeds $seeds --threads 1 "$@" \
  --out "results/synthetic/cnn_object_box/$tag" > "results/synthetic/cnn_object_box/$tag.log" 2>&1
