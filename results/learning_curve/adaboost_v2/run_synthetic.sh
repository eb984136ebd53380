#!/usr/bin/env bash
# Issue 15/16: AdaBoost under protocol halmstad_v2 with its defaults (ensemble box map), 100 real seeds, real only
# and + 20x synthetic from each training seed's own d_HOG fit (the fits the HOG and CNN tables use).
# usage (repository root): results/learning_curve/adaboost_v2/run_synthetic.sh TAG "SEEDS" [runner options...]
# (the runner call is results/synthetic/run_100.sh's, with AdaBoost, the test split and this folder)
set -euo pipefail
tag=$1; seeds=$2; shift 2
# --ada-energy-floor 0: made before AdaBoost's energy floor became its default (stop 49, ../adaboost_scale/README.md).
exec results/synthetic/run_100.sh adaboost "results/learning_curve/adaboost_v2/$tag" test "$seeds" --ada-energy-floor 0 "$@"
