#!/usr/bin/env bash
# AdaBoost (slow to train): the stored detectors scored with the finer pyramid only (--detect-scales), validation
# cells, then test. usage: run_ada.sh SPLIT SEEDS...
set -euo pipefail
split=$1; shift; tag=$(printf %s "$@")
out=results/learning_curve/drone_pyramid
FINE="1.5625 1.25 1.0 0.8 0.64 0.51 0.41"
COMMON="--class drone --detectors adaboost --seed-counts 100 --training-seeds $* --threads 1 --ada-energy-floor 0"  # the paper's energy: run before the floor became the default (stop 49)
extra="--no-scale-check --no-patches --eval-split val"
[ $split = test ] && extra="--no-scale-check"
python -m synthaug.evaluate.runner learning-curve $COMMON $extra --out $out/adaboost_${split}_default_s$tag
python -m synthaug.evaluate.runner learning-curve $COMMON $extra --detect-scales $FINE --out $out/adaboost_${split}_detectfine_s$tag
