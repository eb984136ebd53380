#!/usr/bin/env bash
# Issue 16 item 5, the d_CNN refit started from the CNN's *default* synthetic positives rather than from a d_CNN fit:
# each training seed's d_HOG fit (synthaug fit's defaults, as results/synthetic/run_100.sh's fits) with the CNN's
# family default at generation (boundary and motion blur left out, --effects-off default). Two conditions paired
# against real only: Θ fixed (the CNN's default) and Θ refitted against the CNN after every mining round.
# usage (repository root): results/synthetic/cnn_refit/run_default.sh SPLIT "SEEDS" [OUT]
#   run_default.sh test "0" results/synthetic/cnn_refit/default_test_0   (writes OUT/ and OUT.log)
set -euo pipefail
split=$1; seeds=$2; out=${3:-results/synthetic/cnn_refit/default_$split}
export PYTHONPATH=${PYTHONPATH:-.}
results/synthetic/cnn_dcnn/fit.sh "$seeds" hog
results/synthetic/run_100.sh cnn "$out" "$split" "$seeds" --effects-off default --dcnn-refit off on
