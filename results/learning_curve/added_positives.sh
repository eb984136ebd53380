#!/usr/bin/env bash
# One condition of added real-derived positives (--downscaled-copies, --faded-copies, ...) against real only under the
# protocol, for one training seed (run) or the 3 seeds' cached cells read back together (tables, trains nothing).
# usage: added_positives.sh run OPTION OUT SPLIT FAMILY COPIES SEED
#        added_positives.sh tables OPTION OUT SPLIT FAMILY COPIES
# SPLIT val trains and stores the detector; test reads it back (and keeps the patch protocol on, like the base cells).
set -euo pipefail
mode=$1 option=$2 out=$3 split=$4 family=$5 copies=$6
extra="--no-scale-check --no-patches --eval-split val"
[ "$split" = test ] && extra="--no-scale-check"
if [ "$mode" = run ]; then seeds=$7 name="s$7"; else seeds="0 1 2" name=s012 extra="$extra --read-only"; fi
python -m synthaug.evaluate.runner synthetic --class drone --detectors "$family" --seed-counts 100 \
  --training-seeds $seeds "$option" "$copies" --threads 1 $extra \
  --out "$out/${family}_${split}_x${copies}_${name}"
