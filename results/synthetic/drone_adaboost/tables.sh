#!/usr/bin/env bash
# usage: tables.sh SPLIT RATIO   (the 3 seeds' cached cells; trains nothing)
exec bash "$(dirname "$0")/../../learning_curve/added_positives.sh" tables --synthetic-ratios \
  results/synthetic/drone_adaboost "$1" adaboost "$2" --mesh ../shared/data/meshes/quadcopter.glb
