#!/usr/bin/env bash
# AdaBoost (its protocol defaults) + R synthetic positives per real seed, fitted with its own distance (d_WL^L,
# wl_learned) on each training seed's seed set, against real only, one training seed.
# usage: run.sh SPLIT RATIO SEED   (see ../../learning_curve/added_positives.sh)
exec bash "$(dirname "$0")/../../learning_curve/added_positives.sh" run --synthetic-ratios \
  results/synthetic/drone_adaboost "$1" adaboost "$2" "$3" --mesh ../shared/data/meshes/quadcopter.glb
