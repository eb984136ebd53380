#!/bin/bash
# Stop 80: HOG, 100 seeds, calibrated; the paper's framing and half the synthetic objects framed at the fit's size.
# usage: results/synthetic/box_calibration/hog_mix/run.sh TAG SEED... (from the repository root); two jobs were run,
# `run.sh a 0 1 2 3 4` and `run.sh b 4 3 2 1 0`: the cells are locked, so each cell is made once and both folders
# hold all five seeds (the b folders, identical, are not kept).
tag=$1; shift
O=results/synthetic/box_calibration/hog_mix
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
   --synthetic-ratios 20 --fit-distance hog --no-scale-check --no-patches --threads 1 --seed-counts 100 --box-calibration 20 \
   --object-box none fit --object-box-share 0.5"
export PYTHONPATH=. OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
$R --eval-split val --training-seeds "$@" --out $O/val_$tag > $O/val_$tag.log 2>&1
s1=$(date +%s); echo "val $tag: $((s1-s0)) s" >> $O/times_$tag.txt
$R --eval-split test --training-seeds "$@" --out $O/test_$tag > $O/test_$tag.log 2>&1
s2=$(date +%s); echo "test $tag: $((s2-s1)) s" >> $O/times_$tag.txt
