#!/usr/bin/env bash
# Issue 16: AdaBoost (library defaults: energy floor, 3 mining rounds) + 20x synthetic (d_HOG fits) trained as
# Dynamic-TrAdaBoost (--ada-transfer: the synthetic positives are the source distribution), starting weights by count
# as in the published method, protocol halmstad_v2, 100 seeds, test split, seeds 0 1 2 in two queues (real-only cells
# read back: the option is left out of cells without added positives).
# usage (repository root): results/synthetic/drone_v2_adaboost_transfer/run.sh
set -euo pipefail
D=results/synthetic/drone_v2_adaboost_transfer
( results/synthetic/run_100.sh adaboost $D/transfer_s0 test 0 --ada-transfer
  results/synthetic/run_100.sh adaboost $D/transfer_s2 test 2 --ada-transfer ) &
( results/synthetic/run_100.sh adaboost $D/transfer_s1 test 1 --ada-transfer ) &
wait
# seeds 3 and 4 (real only and + synthetic, one process each), added after seeds 0-2 were read:
#   results/synthetic/run_100.sh adaboost $D/transfer_s3 test 3 --ada-transfer &
#   results/synthetic/run_100.sh adaboost $D/transfer_s4 test 4 --ada-transfer
