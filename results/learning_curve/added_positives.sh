#!/usr/bin/env bash
# One condition of added positives (--downscaled-copies, --faded-copies, --synthetic-ratios, ...) against real only
# under the protocol, for one training seed (run) or the 3 seeds' cached cells read back together (tables, trains
# nothing). Arguments after the fixed ones go to the runner as they are (e.g. --mesh for --synthetic-ratios).
# usage: added_positives.sh run OPTION OUT SPLIT FAMILY COPIES SEED [RUNNER ARGS...]
#        added_positives.sh tables OPTION OUT SPLIT FAMILY COPIES [RUNNER ARGS...]
# SPLIT val trains and stores the detector; test reads it back (and keeps the patch protocol on, like the base cells).
# --ada-cascade all: AdaBoost's soft cascade from every training positive, as these cells were run before the
# real-positive cascade became the default (stop 60); the last value given wins.
# --synthetic-share count: every positive weighs the same, as these cells were run before AdaBoost's default share
# of 0.25 (stop 61); --synthetic-share 0.25 (or any other value given after it) wins.
# --background-sampling seed: each synthetic object on its own seed's background, as these cells were run before the
# CNN's default became other seeds' backgrounds (stop 69); the last value given wins.
set -euo pipefail
mode=$1 option=$2 out=$3 split=$4 family=$5 copies=$6
shift 6
extra="--no-scale-check --no-patches --eval-split val"
[ "$split" = test ] && extra="--no-scale-check"
if [ "$mode" = run ]; then seeds=$1 name="s$1"; shift; else seeds="0 1 2" name=s012 extra="$extra --read-only"; fi
python -m synthaug.evaluate.runner synthetic --class drone --detectors "$family" --seed-counts 100 \
  --training-seeds $seeds "$option" "$copies" --threads 1 $extra --ada-cascade all --synthetic-share count \
  --background-sampling seed "$@" \
  --out "$out/${family}_${split}_x${copies}_${name}"
