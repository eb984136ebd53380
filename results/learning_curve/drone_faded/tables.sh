#!/usr/bin/env bash
# The 3 training seeds' cells (run.sh, one process per seed) read back together: paired tables, trains nothing.
# usage: tables.sh SPLIT FAMILY COPIES
set -euo pipefail
split=$1 family=$2 copies=$3
out=results/learning_curve/drone_faded
extra="--no-scale-check --no-patches --eval-split val"
[ "$split" = test ] && extra="--no-scale-check"
python -m synthaug.evaluate.runner synthetic --class drone --detectors "$family" --seed-counts 100 \
  --training-seeds 0 1 2 --faded-copies "$copies" --threads 1 $extra --read-only \
  --out "$out/${family}_${split}_x${copies}_s012"
