#!/bin/bash
# AdaBoost, 100 real seeds, the mining rule of stop 34 (now AdaBoost's defaults), from the repository root:
#   results/learning_curve/adaboost_mining/run.sh 0 2 &  results/learning_curve/adaboost_mining/run.sh 1
# per training seed: the validation cell (trains and keeps the detector), then the test cell (reads it back).
set -e
O=results/learning_curve/adaboost_mining
export OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
COMMON="--class drone --detectors adaboost --seed-counts 100 --no-scale-check --ada-rounds 300 --mining-select ap --mining-patience 1 --ada-energy-floor 0"  # the paper's energy: run before the floor became the default (stop 49)
for s in "$@"; do
  python -m synthaug.evaluate.runner learning-curve $COMMON --no-patches --eval-split val --seeds $s --out $O/val_r300ap_seed$s > $O/val_r300ap_seed$s.log 2>&1
  python -m synthaug.evaluate.runner learning-curve $COMMON --seeds $s --out $O/test_r300ap_seed$s > $O/test_r300ap_seed$s.log 2>&1
done
