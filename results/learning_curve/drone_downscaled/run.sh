#!/usr/bin/env bash
# Issue 15, AdaBoost's small drones: the 100 real seeds + COPIES downscaled copies of each (longest side 16-24 px, cut
# down to the pyramid's x1.25), paired against real only (the cached cell). usage: run.sh SPLIT FAMILY COPIES SEED
set -euo pipefail
split=$1 family=$2 copies=$3 seed=$4
out=results/learning_curve/drone_downscaled
extra="--no-scale-check --no-patches --eval-split val"
[ "$split" = test ] && extra="--no-scale-check"
python -m synthaug.evaluate.runner synthetic --class drone --detectors "$family" --seed-counts 100 \
  --training-seeds "$seed" --downscaled-copies "$copies" --threads 1 $extra \
  --out "$out/${family}_${split}_x${copies}_s${seed}"
