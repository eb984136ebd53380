#!/usr/bin/env bash
# Issue 16 / the paper's Table 2 under protocol halmstad_v2: which fit distance makes the synthetic positives that
# help each detector. Drones, test split, 100 real seeds + 20x synthetic, training seeds 0-2, every fitted effect
# (run_100.sh pins --effects-off none), one fit per training seed and distance (synthaug fit's defaults).
# usage (repository root): results/synthetic/table2/run.sh hog|cnn
#   hog: real only, d_HOG, d_Eucl, d_CNN fits, HOG detector; cnn: d_HOG and d_Eucl fits, CNN detector (its real only
#   and d_CNN cells are those of ../cnn_dcnn/, made on the same machine and read back from the cell cache).
set -euo pipefail
export PYTHONPATH=${PYTHONPATH:-.}
D=results/synthetic/table2; R=results/synthetic/run_100.sh; F='data/runs/fits/drone_100_seed{seed}'
case $1 in
  hog)
    results/synthetic/cnn_dcnn/fit.sh "0 1 2" eucl      # the d_Eucl fits (the CNN chain waits for them)
    for dist in hog eucl cnn; do
      $R hog $D/hog_$dist test "0 1 2" --params "${F}_${dist}.json"
    done ;;
  cnn)
    $R cnn $D/cnn_hog test "0 1 2" --params "${F}_hog.json"
    for s in 0 1 2; do while [ ! -f data/runs/fits/drone_100_seed${s}_eucl.json ]; do sleep 30; done; done
    $R cnn $D/cnn_eucl test "0 1 2" --params "${F}_eucl.json" ;;
esac
