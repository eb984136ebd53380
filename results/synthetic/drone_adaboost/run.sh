#!/usr/bin/env bash
# AdaBoost (its protocol defaults) + R synthetic positives per real seed, fitted with its own distance (d_WL^L,
# wl_learned) on each training seed's seed set, against real only, one training seed.
# usage: run.sh SPLIT RATIO SEED [SHARE]   (see ../../learning_curve/added_positives.sh)
# SHARE: --synthetic-share (the synthetic positives' share of the positives' starting weight); its cells go to
# results/synthetic/drone_adaboost_share (stop 39 measured SHARE 0.25 there).
out=results/synthetic/drone_adaboost share=()
if [ -n "${4:-}" ]; then out=results/synthetic/drone_adaboost_share share=(--synthetic-share "$4"); fi
exec bash "$(dirname "$0")/../../learning_curve/added_positives.sh" run --synthetic-ratios \
  "$out" "$1" adaboost "$2" "$3" --mesh ../shared/data/meshes/quadcopter.glb "${share[@]}" \
  --ada-energy-floor 0  # the paper's energy: run before the floor became AdaBoost's default (stop 49)
