#!/usr/bin/env bash
# Issue 16: the CNN + 20x synthetic (d_HOG fits of each training seed's 100-seed set), with and without fine-tuning
# on the real positives afterwards (TrainOptions.cnn_finetune_epochs), protocol halmstad_v2, default (ensemble) box map.
# usage (repository root): results/synthetic/cnn_finetune/run.sh TAG SPLIT "SEEDS" [runner options...]
#   run.sh val_plain val "0 1 2"
#   run.sh val_ft4 val "0 1 2" --cnn-finetune-epochs 4
set -euo pipefail
tag=$1; split=$2; seeds=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors cnn --seed-counts 100 --synthetic-ratios 20 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' \
  --no-scale-check --no-patches --eval-split "$split" --training-seeds $seeds --threads 1 "$@" \
  --out "results/synthetic/cnn_finetune/$tag" > "results/synthetic/cnn_finetune/$tag.log" 2>&1
