#!/bin/bash
# Stop 86: AdaBoost, drones, 100 seeds, + 20x synthetic with the HOG realism critic (each seed keeps the quarter of its
# own draws it finds least synthetic, HOG's default since stop 83) against real only and against every draw.
# The library's AdaBoost defaults otherwise (share 0.25, real-positive cascade), d_HOG fits of quadcopter.glb made by
# the runner (as stops 61-63's AdaBoost rows: their fits used the .glb mesh too).
# usage (repository root): results/synthetic/adaboost_critic/run.sh TAG SEED KEEP...
#   trains on the validation split's mining (scoring it), then reads the detectors back to score the test split.
# Run parallel jobs on disjoint seeds (a seed set's fit is not locked).
tag=$1; seed=$2; shift 2
O=results/synthetic/adaboost_critic
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
   --detectors adaboost --seed-counts 100 --synthetic-ratios 20 --fit-distance hog \
   --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --threads 1 --realism-keep $*"
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
$R --eval-split val --training-seeds $seed --out $O/val_$tag > $O/val_$tag.log 2>&1
s1=$(date +%s); echo "val $tag (seed $seed, keep $*): $((s1-s0)) s" >> $O/times.txt
$R --eval-split test --training-seeds $seed --out $O/test_$tag > $O/test_$tag.log 2>&1
s2=$(date +%s); echo "test $tag (seed $seed, keep $*): $((s2-s1)) s" >> $O/times.txt
