#!/bin/bash
# Stop 81: HOG, 100 seeds, calibrated, test split: the paper's perturbation (20 copies of each real seed) or
# copy-paste (20 per seed, the d_HOG fits' silhouettes), beside stops 79-80's real-only and synthetic cells.
# usage (from the repository root): results/synthetic/box_calibration/hog_baselines/run.sh perturbed|copy_paste SEED...
# (out: $O/<what>, or $O/<what>_<first seed>_<last seed> when TAG=1 is set)
what=$1; shift
O=results/synthetic/box_calibration/hog_baselines
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone --detectors hog \
   --fit-distance hog --no-scale-check --no-patches --threads 1 --seed-counts 100 --box-calibration 20 --eval-split test"
case $what in
  perturbed) X="--perturb-copies 20";;
  copy_paste) X="--copy-paste-ratios 20";;
  *) echo "usage: $0 perturbed|copy_paste SEED..." >&2; exit 2;;
esac
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
t0=$(date +%s)
out=$what; [ -n "${TAG:-}" ] && out=${what}_$1_${@: -1}
$R $X --training-seeds "$@" --out $O/$out > $O/$out.log 2>&1
echo "$what $*: $(( $(date +%s) - t0 )) s" >> $O/times.txt
