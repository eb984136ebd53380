#!/bin/bash
# Stop 97: AdaBoost's stored detectors (real only and the shape cell of ../adaboost_wl_critic/, 100 drone seeds)
# read back and scored with the box calibration HOG and the CNN have by default since stop 73 (every 20th labelled
# frame of the training videos). Trains nothing: both detectors of each seed must be in data/runs/cells/detectors;
# --read-only is not used because the calibrated cells are new cells (the calibration is part of the cell's key, not
# of the detector's).
# usage (repository root): results/synthetic/adaboost_rounds/run_calibration.sh SPLIT TAG SEED [SEED ...]
split=$1; tag=$2; shift 2
O=results/synthetic/adaboost_rounds
R="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
   --detectors adaboost --seed-counts 100 --no-scale-check --no-patches --threads 1 \
   --synthetic-ratios 20 --fit-distance hog --mesh ../shared/data/meshes/quadcopter.glb \
   --realism-keep 0.25 --realism-features weak_learners --quantize on --pose-sampling fitted_at_seed \
   --shape-variation 0.3 --box-calibration 20"
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
$R --eval-split $split --training-seeds "$@" --out $O/cal_${split}_$tag > $O/cal_${split}_$tag.log 2>&1
echo "cal $split $tag (seeds $*): $(( $(date +%s) - s0 )) s" >> $O/times.txt
