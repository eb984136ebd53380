#!/usr/bin/env bash
# Issue 15, the faint test drones: the 100 real seeds + COPIES faded copies of each (the object's difference from its
# own background patch scaled by x0.3-0.9 inside the box), paired against real only (the cached cell).
# usage: run.sh SPLIT FAMILY COPIES SEED    (val trains and stores the detector; test reads it back)
set -euo pipefail
split=$1 family=$2 copies=$3 seed=$4
out=results/learning_curve/drone_faded
extra="--no-scale-check --no-patches --eval-split val"
[ "$split" = test ] && extra="--no-scale-check"
python -m synthaug.evaluate.runner synthetic --class drone --detectors "$family" --seed-counts 100 \
  --training-seeds "$seed" --faded-copies "$copies" --threads 1 $extra \
  --out "$out/${family}_${split}_x${copies}_s${seed}"
