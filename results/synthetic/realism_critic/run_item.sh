#!/bin/bash
# Stop 84: the critic's lazy form (--realism-selection item: each patch the least synthetic of its own 4 candidates,
# which keep its seed, as SyntheticObjectDataset's realism_critic draws) against stop 83's per-seed quarter (seed) and
# real only (every draw left out: stop 83 measured it). HOG, drones, calibrated, + 20x synthetic, both splits.
# usage (from the repository root): results/synthetic/realism_critic/run_item.sh SEEDCOUNT SEED...
# Each training seed in turn, validation (trains) then test (reads the detectors back); jobs on disjoint seeds.
n=$1; shift
O=results/synthetic/realism_critic/per_item_$n
mkdir -p $O
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
   --synthetic-ratios 20 --fit-distance hog --no-scale-check --no-patches --threads 1 --seed-counts $n --box-calibration 20 \
   --realism-keep 0.25 --realism-selection seed item"
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
for s in "$@"; do
  t0=$(date +%s)
  $R --eval-split val --training-seeds $s --out $O/val_$s > $O/val_$s.log 2>&1
  t1=$(date +%s)
  $R --eval-split test --training-seeds $s --out $O/test_$s > $O/test_$s.log 2>&1
  t2=$(date +%s); echo "seed $s: val $((t1-t0)) s, test $((t2-t1)) s" >> $O/times.txt
done
