#!/usr/bin/env bash
# A finer pyramid level (x1.5625 = 1.25^2, drones down to ~18 px) for one family, validation then test cells.
# usage: run.sh FAMILY   (hog | cnn); the default pyramid's cells are computed beside it, same seeds.
set -euo pipefail
fam=$1
out=results/learning_curve/drone_pyramid
FINE="1.5625 1.25 1.0 0.8 0.64 0.51 0.41"
COMMON="--class drone --detectors $fam --seed-counts 100 --training-seeds 0 1 2 --threads 1"
for split in val test; do
  extra="--no-scale-check --no-patches --eval-split val"
  [ $split = test ] && extra=""
  python -m synthaug.evaluate.runner learning-curve $COMMON $extra --out $out/${fam}_${split}_default
  python -m synthaug.evaluate.runner learning-curve $COMMON $extra --scales $FINE --out $out/${fam}_${split}_fine
done
