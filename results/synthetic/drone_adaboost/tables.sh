#!/usr/bin/env bash
# usage: tables.sh SPLIT RATIO [SHARE]   (the 3 seeds' cached cells; trains nothing; SHARE as in run.sh)
out=results/synthetic/drone_adaboost share=()
if [ -n "${3:-}" ]; then out=results/synthetic/drone_adaboost_share share=(--synthetic-share "$3"); fi
exec bash "$(dirname "$0")/../../learning_curve/added_positives.sh" tables --synthetic-ratios \
  "$out" "$1" adaboost "$2" --mesh ../shared/data/meshes/quadcopter.glb "${share[@]}"
