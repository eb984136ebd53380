#!/bin/bash
# Stop 80: HOG, 12 seeds, calibrated: real, + 20x synthetic (the paper's framing), + 20x with half the objects framed
# at the fit's size. usage (from the repository root): results/synthetic/box_calibration_12/mix/run.sh TAG SEED...
# Each training seed in turn, validation (trains) then test (reads the detectors back); two jobs on disjoint seeds
# (`run.sh a 0 2 4`, `run.sh b 1 3`), so no two processes ingest or fit the same seed set.
tag=$1; shift
O=results/synthetic/box_calibration_12/mix
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
   --synthetic-ratios 20 --fit-distance hog --no-scale-check --no-patches --threads 1 --seed-counts 12 --box-calibration 20 \
   --object-box none fit --object-box-share 0.5"
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
for s in "$@"; do
  t0=$(date +%s)
  $R --eval-split val --training-seeds $s --out $O/val_$s > $O/val_$s.log 2>&1
  t1=$(date +%s)
  $R --eval-split test --training-seeds $s --out $O/test_$s > $O/test_$s.log 2>&1
  t2=$(date +%s); echo "seed $s: val $((t1-t0)) s, test $((t2-t1)) s" >> $O/times_$tag.txt
done
