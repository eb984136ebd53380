#!/bin/bash
# Stop 81: HOG, 100 seeds, calibrated, training seeds 5-9 added to stops 79-80's 0-4 (the library's defaults: the
# paper's framing, + 20x synthetic from each seed set's own d_HOG fit), both splits.
# usage: results/synthetic/box_calibration/hog_10seeds/run.sh TAG SEED... (from the repository root); run as
# `run.sh a 5 7 9 & run.sh b 6 8` (disjoint seeds: a seed set's ingest and fit are not locked).
tag=$1; shift
O=results/synthetic/box_calibration/hog_10seeds
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
   --synthetic-ratios 20 --fit-distance hog --no-scale-check --no-patches --threads 1 --seed-counts 100 --box-calibration 20"
export PYTHONPATH=. OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
$R --eval-split val --training-seeds "$@" --out $O/val_$tag > $O/val_$tag.log 2>&1
s1=$(date +%s); echo "val $tag: $((s1-s0)) s" >> $O/times_$tag.txt
$R --eval-split test --training-seeds "$@" --out $O/test_$tag > $O/test_$tag.log 2>&1
s2=$(date +%s); echo "test $tag: $((s2-s1)) s" >> $O/times_$tag.txt
