#!/bin/bash
# Stop 105 (issue 16): AdaBoost's recipe (its family default since stop 104: fitted rotations at the seeds' offsets,
# shapes +-30 %, 8-bit, the weak-learner critic's quarter, 5 soft distractors per seed) on the airplanes, against real
# only and the former defaults (the paper's draws, share 0.25). Today's defaults otherwise (box calibration every 20th
# frame, the real-positive cascade, share 0.25); the airplanes' pyramid (to 0.26) and mesh; test split; one training
# seed a call, two calls side by side on the 2 cores. The runner trains the added cell, then real only (cached).
# usage (repository root): results/synthetic/airplane_v2/adaboost_recipe/run.sh recipe|former SEED OUT [--read-only]
# SEED_COUNT=100 for the 100-seed sets (default 12).
# `recipe` is AdaBoost's default: its 8-bit rounding until stop 107 (the stored twelve_s* cells, seeds 3-4 included),
# native-scale rounding since stop 108; add --quantize on to repeat the 8-bit cells.
mode=$1; seed=$2; out=$3; shift 3
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
# 8 shapes of the airplane + 8 blobs: the default 1 GB sprite cache would evict them in turn
export SYNTHAUG_CACHE=${SYNTHAUG_CACHE:-data/sprite_cache_distractors}
export SYNTHAUG_CACHE_MAX_MB=${SYNTHAUG_CACHE_MAX_MB:-8000}
case $mode in
  recipe) draws=();;
  former) draws=(--pose-sampling uniform --shape-variation 0 --quantize off --realism-keep 1 --distractor-ratio 0);;
  *) echo "mode: recipe or former" >&2; exit 2;;
esac
s0=$(date +%s)
python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class airplane \
   --detectors adaboost --seed-counts "${SEED_COUNT:-12}" --no-scale-check --no-patches --threads 1 \
   --synthetic-ratios 20 --fit-distance hog --mesh ../shared/data/meshes/twin_prop_airplane.glb \
   --scales 1.25 1.0 0.8 0.64 0.51 0.41 0.33 0.26 "${draws[@]}" \
   --eval-split test --training-seeds "$seed" --out "$out" "$@"
echo "airplanes $mode seed $seed ${SEED_COUNT:-12} seeds $*: $(( $(date +%s) - s0 )) s"
