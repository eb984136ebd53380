#!/bin/bash
# Stop 86: a seed's real-only cell and its added cell in two processes at once (run.sh trains them one after the
# other in one runner call). Same set-up as run.sh.
# usage (repository root): results/synthetic/adaboost_critic/run2.sh real TAG SEED
#                          results/synthetic/adaboost_critic/run2.sh added TAG SEED KEEP...
mode=$1; tag=$2; seed=$3; shift 3
O=results/synthetic/adaboost_critic
A="--protocol configs/protocol/halmstad_v2.json --class drone --detectors adaboost --seed-counts 100 \
   --no-scale-check --no-patches --threads 1"
if [ "$mode" = real ]; then
  R="python -m synthaug.evaluate.runner synthetic $A"
else
  R="python $O/added_only.py synthetic $A --synthetic-ratios 20 --fit-distance hog \
     --mesh ../shared/data/meshes/quadcopter.glb --realism-keep $*"
fi
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
$R --eval-split val --training-seeds $seed --out $O/val_$tag > $O/val_$tag.log 2>&1
s1=$(date +%s); echo "val $tag ($mode, seed $seed, keep $*): $((s1-s0)) s" >> $O/times.txt
$R --eval-split test --training-seeds $seed --out $O/test_$tag > $O/test_$tag.log 2>&1
s2=$(date +%s); echo "test $tag ($mode, seed $seed, keep $*): $((s2-s1)) s" >> $O/times.txt
