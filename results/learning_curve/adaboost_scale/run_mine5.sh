#!/usr/bin/env bash
# Issue 16: AdaBoost (energy floor, the default) with 5 hard-negative mining rounds instead of 3, real only and
# + 20x synthetic (d_HOG fits), protocol halmstad_v2, 100 seeds, seeds 0 1 2, two queues on the 2 cores.
# usage (repository root): results/learning_curve/adaboost_scale/run_mine5.sh
set -euo pipefail
A=results/learning_curve/adaboost_scale
( results/learning_curve/adaboost_scale/run_floor.sh mine5_s2 2 1 --mining-rounds 5 --no-scale-check
  results/synthetic/run_100.sh adaboost $A/mine5_syn_s0 test 0 --mining-rounds 5 ) &
( results/synthetic/run_100.sh adaboost $A/mine5_syn_s1 test 1 --mining-rounds 5
  results/synthetic/run_100.sh adaboost $A/mine5_syn_s2 test 2 --mining-rounds 5 ) &
wait
