#!/bin/bash
# Stop 101: AdaBoost's shape cell (../adaboost_rounds/run_calibration.sh's condition, the box calibration on) with K
# rendered distractors per real seed added to its negatives (--distractor-ratio), frame level, test split, one
# training seed a call (two calls side by side on 2 cores). The real-only and shape cells it is paired with are the
# stored Intel Xeon ones of intel_cal_test/ (this machine kind repeats them bit for bit: fingerprints.py).
# The runner trains real only after the added cell: once the log shows the added cell's "seed S: cell done" line, the
# call may be stopped and the cell's JSON written from the cache by the same call with --read-only appended.
# usage (repository root): results/synthetic/adaboost_distractors/run_frame.sh K SEED OUT [--read-only]
# SEED_COUNT=12 runs the same cells on a 12-seed set (stop 104; default 100).
k=$1; seed=$2; out=$3; shift 3
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
# 8 shapes of the drone + 8 blobs: the default 1 GB sprite cache would evict them in turn
export SYNTHAUG_CACHE=${SYNTHAUG_CACHE:-data/sprite_cache_distractors}
export SYNTHAUG_CACHE_MAX_MB=${SYNTHAUG_CACHE_MAX_MB:-8000}
s0=$(date +%s)
python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
   --detectors adaboost --seed-counts "${SEED_COUNT:-100}" --no-scale-check --no-patches --threads 1 \
   --synthetic-ratios 20 --fit-distance hog --mesh ../shared/data/meshes/quadcopter.glb \
   --realism-keep 0.25 --realism-features weak_learners --quantize on --pose-sampling fitted_at_seed \
   --shape-variation 0.3 --box-calibration 20 --distractor-ratio "$k" \
   --eval-split test --training-seeds "$seed" --out "$out" "$@"
echo "distractors $k seed $seed $*: $(( $(date +%s) - s0 )) s"
