#!/usr/bin/env bash
# Issue 16 item 5: the paper's d_CNN refit redone under protocol halmstad_v2. Drones, 100 real seeds + 20x synthetic
# from each training seed's own d_CNN fit (results/synthetic/cnn_dcnn/fit.sh), every fitted effect (as that row of
# Table 1), the CNN at the protocol's defaults; two conditions paired against real only: Θ fixed (the fit before
# training) and Θ refitted against the CNN after every mining round (--dcnn-refit on).
# usage (repository root): results/synthetic/cnn_refit/run.sh SPLIT "SEEDS" [OUT]
#   run.sh test "0 2 4" results/synthetic/cnn_refit/test_a   (writes OUT/ and OUT.log)
set -euo pipefail
split=$1; seeds=$2; out=${3:-results/synthetic/cnn_refit/$split}
export PYTHONPATH=${PYTHONPATH:-.}
results/synthetic/cnn_dcnn/fit.sh "$seeds"
results/synthetic/run_100.sh cnn "$out" "$split" "$seeds" --params 'data/runs/fits/drone_100_seed{seed}_cnn.json' \
  --dcnn-refit off on
