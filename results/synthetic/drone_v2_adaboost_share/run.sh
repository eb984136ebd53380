#!/usr/bin/env bash
# Issue 16: AdaBoost (library defaults: energy floor, 3 mining rounds) + 20x synthetic (d_HOG fits) with the real
# seeds keeping 3/4 of the positives' starting weight (--synthetic-share 0.25, the CNN's share, fixed before the run),
# protocol halmstad_v2, 100 seeds, test split, seeds 0 1 2 in two queues on the 2 cores (real-only cells read back).
# usage (repository root): results/synthetic/drone_v2_adaboost_share/run.sh
set -euo pipefail
D=results/synthetic/drone_v2_adaboost_share
( results/synthetic/run_100.sh adaboost $D/share25_s0 test 0 --synthetic-share 0.25
  results/synthetic/run_100.sh adaboost $D/share25_s2 test 2 --synthetic-share 0.25 ) &
( results/synthetic/run_100.sh adaboost $D/share25_s1 test 1 --synthetic-share 0.25 ) &
wait
