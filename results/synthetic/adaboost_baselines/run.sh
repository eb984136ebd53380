#!/usr/bin/env bash
# Issue 16, Table 1's AdaBoost row under protocol halmstad_v2: real only, + 20x perturbed (the paper's baseline),
# + 20x copy-paste (d_HOG fit silhouettes) and + 20x synthetic (d_HOG fits), the added positives of every condition
# trained with the transfer rule (--ada-transfer, AdaBoost's best rule for added positives since stop 51; the real-only
# cell has none, so the option leaves it unchanged). Drones, test split, 100 real seeds, training seeds 0-2, every cell
# trained on one machine: one chain per training seed (three on the 2 cores), then the three seeds read back together.
# usage (repository root): results/synthetic/adaboost_baselines/run.sh
# (Stop 56 trained the real-only cells first (seed$s.log), then ran the chains; their synthetic step was not run.
# The synthetic cells were trained by run_100.sh, one process per seed (stops 56-57; seed{0,1,2}_synthetic.log).)
set -euo pipefail
export PYTHONPATH=${PYTHONPATH:-.}
D=results/synthetic/adaboost_baselines; R=results/synthetic/run_100.sh
chain() {  # real only and the two baselines, then the synthetic cell (read-back of real only)
  $R adaboost $D/seed${1}_baselines test "$1" --ada-transfer --synthetic-ratios \
    --perturb-copies 20 --copy-paste-ratios 20
  $R adaboost $D/seed${1}_synthetic test "$1" --ada-transfer
}
for s in 0 1 2; do chain $s & done
wait
$R adaboost $D/all test "0 1 2" --ada-transfer --perturb-copies 20 --copy-paste-ratios 20 --read-only
