#!/bin/bash
# Stop 87: AdaBoost, drones, 100 seeds, + 20x synthetic with a realism critic in AdaBoost's own features (the
# edge-orientation energies of 2,000 random Levi-Weiss rectangles at AdaBoost's energy floor; each seed keeps the
# quarter of its own draws the critic finds least synthetic), trained while scoring the validation split, then read
# back to score the test split. Real only comes from the cell cache (stop 86's cells, the same key) when it is there.
# usage (repository root): results/synthetic/adaboost_wl_critic/run.sh TAG SEED [RUNNER FLAGS...]
#   e.g. run.sh q0 0 --quantize on   (the synthetic positives rounded to 8-bit levels, the critic scoring them so)
# Run parallel jobs on disjoint seeds (a seed set's fit is not locked). RUNNER=".../adaboost_critic/added_only.py" skips
# the real-only cell (stop 88's q2, beside ../adaboost_critic/run2.sh real r2 2); since stop 88 the runner trains real
# only last anyway, so a plain run.sh beside run2.sh real reads it back at its end (q3).
tag=$1; seed=$2; shift 2
O=results/synthetic/adaboost_wl_critic
R="${RUNNER:-python -m synthaug.evaluate.runner} synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
   --detectors adaboost --seed-counts 100 --no-scale-check --no-patches --threads 1 \
   --synthetic-ratios 20 --fit-distance hog --mesh ../shared/data/meshes/quadcopter.glb \
   --realism-keep 0.25 --realism-features weak_learners $*"
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
$R --eval-split val --training-seeds $seed --out $O/val_$tag > $O/val_$tag.log 2>&1
s1=$(date +%s); echo "val $tag (seed $seed $*): $((s1-s0)) s" >> $O/times.txt
$R --eval-split test --training-seeds $seed --out $O/test_$tag > $O/test_$tag.log 2>&1
s2=$(date +%s); echo "test $tag (seed $seed $*): $((s2-s1)) s" >> $O/times.txt
