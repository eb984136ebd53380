#!/bin/bash
# stop 106: AdaBoost's recipe (its default) and 12 real on the airplanes, 12 seeds, with the pyramid's levels rounded
# to 8 bits (runner_8bit.py), against the stored cells of ../airplane_v2/adaboost_recipe (the same calls, float levels).
# usage (repository root): results/synthetic/pyramid_8bit/run.sh SEED OUT [runner options]
seed=$1; out=$2; shift 2
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
export SYNTHAUG_CACHE=${SYNTHAUG_CACHE:-data/sprite_cache_distractors}
export SYNTHAUG_CACHE_MAX_MB=${SYNTHAUG_CACHE_MAX_MB:-8000}
W=${WORK:-data/runs_pyr8}
mkdir -p $W
[ -e $W/fits ] || ln -s ../runs/fits $W/fits   # the same d_HOG fits (they never read the pyramid)
s0=$(date +%s)
python results/synthetic/pyramid_8bit/runner_8bit.py synthetic --work $W --protocol configs/protocol/halmstad_v2.json \
   --class airplane --detectors adaboost --seed-counts "${SEED_COUNT:-12}" --no-scale-check --no-patches --threads 1 \
   --synthetic-ratios 20 --fit-distance hog --mesh ../shared/data/meshes/twin_prop_airplane.glb \
   --scales 1.25 1.0 0.8 0.64 0.51 0.41 0.33 0.26 --eval-split test --training-seeds "$seed" --out "$out" "$@"
echo "airplanes, 8-bit pyramid, seed $seed ${SEED_COUNT:-12} seeds $*: $(( $(date +%s) - s0 )) s"
