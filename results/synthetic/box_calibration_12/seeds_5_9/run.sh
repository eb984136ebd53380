#!/bin/bash
# Stop 81: HOG, 12 seeds, calibrated: real and + 20x synthetic (the paper's framing, the default) for training seeds
# beyond stop 80's 0-4, against the 100-seed cells of ../../box_calibration/hog_10seeds/ (same training seeds).
# usage (from the repository root): results/synthetic/box_calibration_12/seeds_5_9/run.sh TAG SEED...
# Each training seed in turn, validation (trains) then test (reads the detectors back); jobs on disjoint seeds.
tag=$1; shift
O=results/synthetic/box_calibration_12/seeds_5_9
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
   --synthetic-ratios 20 --fit-distance hog --no-scale-check --no-patches --threads 1 --seed-counts 12 --box-calibration 20"
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
for s in "$@"; do
  t0=$(date +%s)
  $R --eval-split val --training-seeds $s --out $O/val_$s > $O/val_$s.log 2>&1
  t1=$(date +%s)
  $R --eval-split test --training-seeds $s --out $O/test_$s > $O/test_$s.log 2>&1
  t2=$(date +%s); echo "seed $s: val $((t1-t0)) s, test $((t2-t1)) s" >> $O/times_$tag.txt
done
