#!/usr/bin/env bash
# Issue 16: the CNN + 20x synthetic (d_HOG fits of each training seed's 100-seed set), with and without fine-tuning
# on the real positives afterwards (TrainOptions.cnn_finetune_epochs), protocol halmstad_v2, default (ensemble) box map.
# usage (repository root): results/synthetic/cnn_finetune/run.sh TAG SPLIT "SEEDS" [runner options...]
#   run.sh val_plain val "0 1 2"
#   run.sh val_ft4 val "0 1 2" --cnn-finetune-epochs 4
# (the runner call is ../run_100.sh's, with the CNN and this folder)
set -euo pipefail
tag=$1; split=$2; seeds=$3; shift 3
exec results/synthetic/run_100.sh cnn "results/synthetic/cnn_finetune/$tag" "$split" "$seeds" "$@"
