#!/bin/bash
# Stop 82: HOG, 12 seeds, calibrated, + 20x synthetic with the realism critic (--realism-keep KEEP) beside the
# paper's draw; the real-only and unfiltered cells are stops 80-81's (read back from the cache). Stop 82's selection
# over the whole draw (--realism-selection set; the default since stop 83 is seed: run_seed.sh).
# usage (from the repository root): results/synthetic/realism_critic/run12.sh TAG KEEP SEED...
# Each training seed in turn, validation (trains) then test (reads the detectors back); jobs on disjoint seeds.
tag=$1; keep=$2; shift 2
O=results/synthetic/realism_critic/s12
mkdir -p $O
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
   --synthetic-ratios 20 --fit-distance hog --no-scale-check --no-patches --threads 1 --seed-counts 12 --box-calibration 20 \
   --realism-keep 1 $keep --realism-selection set"
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
for s in "$@"; do
  t0=$(date +%s)
  $R --eval-split val --training-seeds $s --out $O/val_$s > $O/val_$s.log 2>&1
  t1=$(date +%s)
  $R --eval-split test --training-seeds $s --out $O/test_$s > $O/test_$s.log 2>&1
  t2=$(date +%s); echo "seed $s (keep $keep): val $((t1-t0)) s, test $((t2-t1)) s" >> $O/times_$tag.txt
done
