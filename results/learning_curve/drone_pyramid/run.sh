#!/usr/bin/env bash
# A finer pyramid level (x1.5625 = 1.25^2: drones down to ~18 px) for one family, against the default pyramid,
# same seeds and the same trained detectors: validation cells (the choice), then test cells (no scale check, for time).
# usage: run.sh FAMILY [STEP...]   FAMILY: hog | cnn
#   STEPs (default, in order): val_default val_detectfine test_default test_detectfine
#   *_default: the default pyramid (trains the detectors, 3 training seeds; the test cells read them back);
#   *_detectfine: the same stored detectors scored with the level added (--detect-scales);
#   *_fine: the level in mining and validation too (--scales; trains other detectors; not run in stop 35, for time).
set -euo pipefail
fam=$1; shift
steps=${*:-val_default val_detectfine test_default test_detectfine}
out=results/learning_curve/drone_pyramid
FINE="1.5625 1.25 1.0 0.8 0.64 0.51 0.41"
COMMON="--class drone --detectors $fam --seed-counts 100 --training-seeds 0 1 2 --threads 1"
for step in $steps; do
  split=${step%_*}; pyr=${step#*_}
  extra="--no-scale-check --no-patches --eval-split val"
  [ "$split" = test ] && extra="--no-scale-check"
  case $pyr in
    default) scales="" ;;
    detectfine) scales="--detect-scales $FINE" ;;
    fine) scales="--scales $FINE" ;;
    *) echo "unknown step $step" >&2; exit 2 ;;
  esac
  python -m synthaug.evaluate.runner learning-curve $COMMON $extra $scales --out $out/${fam}_${step}
done
