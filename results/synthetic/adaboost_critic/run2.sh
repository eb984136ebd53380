#!/bin/bash
# Stop 86: AdaBoost, drones, 100 seeds, + 20x synthetic with the HOG realism critic, trained while scoring the
# validation split, then read back to score the test split (the set-up: README.md).
# usage (repository root): results/synthetic/adaboost_critic/run2.sh both TAG SEED KEEP...  (run.sh: real only, then
#                            the added cells, in one runner call)
#                          results/synthetic/adaboost_critic/run2.sh real TAG SEED          (the real-only cell alone)
#                          results/synthetic/adaboost_critic/run2.sh added TAG SEED KEEP... (the added cells alone)
# "real" and "added" let a seed's two cells train in two processes at once (added_only.py). Run parallel jobs on
# disjoint seeds otherwise (a seed set's fit is not locked).
mode=$1; tag=$2; seed=$3; shift 3
O=results/synthetic/adaboost_critic
A="--protocol configs/protocol/halmstad_v2.json --class drone --detectors adaboost --seed-counts 100 \
   --no-scale-check --no-patches --threads 1"
S="--synthetic-ratios 20 --fit-distance hog --mesh ../shared/data/meshes/quadcopter.glb --realism-keep $*"
case $mode in
  real) R="python -m synthaug.evaluate.runner synthetic $A" ;;
  added) R="python $O/added_only.py synthetic $A $S" ;;
  both) R="python -m synthaug.evaluate.runner synthetic $A $S" ;;
  *) echo "mode must be real, added or both, got $mode" >&2; exit 2 ;;
esac
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
$R --eval-split val --training-seeds $seed --out $O/val_$tag > $O/val_$tag.log 2>&1
s1=$(date +%s); echo "val $tag ($mode, seed $seed, keep $*): $((s1-s0)) s" >> $O/times.txt
$R --eval-split test --training-seeds $seed --out $O/test_$tag > $O/test_$tag.log 2>&1
s2=$(date +%s); echo "test $tag ($mode, seed $seed, keep $*): $((s2-s1)) s" >> $O/times.txt
