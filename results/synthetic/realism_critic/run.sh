#!/bin/bash
# Stop 82: HOG, 100 seeds, calibrated, the library's defaults (paper framing, + 20x synthetic from each seed set's d_HOG
# fit) with the synthetic positives filtered by a realism critic in HOG features (--realism-keep K: 20/K x drawn, the K
# least synthetic kept), both splits; real-only and unfiltered cells are stops 79-81's (read back from the cache).
# usage (from the repository root): results/synthetic/realism_critic/run.sh TAG KEEP SEED...
# (run parallel jobs on disjoint seeds: a seed set's fit is not locked). X="..." adds runner options, and then only KEEP
# is run (e.g. X="--quantize on" run.sh e 0.5 0 1 2: the 8-bit positives, half kept). Stop 82's selection over the
# whole draw (--realism-selection set; the default since stop 83 is seed: run_seed.sh).
tag=$1; keep=$2; shift 2
O=results/synthetic/realism_critic
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
   --synthetic-ratios 20 --fit-distance hog --no-scale-check --no-patches --threads 1 --seed-counts 100 --box-calibration 20 \
   --realism-selection set ${X:---realism-keep 1 $keep}"
[ -n "${X:-}" ] && R="$R --realism-keep $keep"
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
$R --eval-split val --training-seeds "$@" --out $O/val_$tag > $O/val_$tag.log 2>&1
s1=$(date +%s); echo "val $tag (keep $keep, seeds $*): $((s1-s0)) s" >> $O/times_$tag.txt
$R --eval-split test --training-seeds "$@" --out $O/test_$tag > $O/test_$tag.log 2>&1
s2=$(date +%s); echo "test $tag (keep $keep, seeds $*): $((s2-s1)) s" >> $O/times_$tag.txt
