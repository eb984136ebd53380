#!/bin/bash
# stop 107 (issue 16): AdaBoost's recipe with its 8-bit rounding moved or split (runner_rounding.py MODE), one training
# seed a call, two calls side by side on the 2 cores. The calls are those of the stored recipe cells each is paired
# with: drones, 100 seeds (../adaboost_distractors/run_frame.sh 5 S OUT --distractor-style soft) and airplanes, 12 seeds
# (../airplane_v2/adaboost_recipe/run.sh recipe S OUT). The runner trains real only after the added cell (stored
# already): the call is stopped once its log shows the added cell done, and the cell's JSON written from the cache by
# the same call with --read-only. Each mode works in its own folder (data/runs_MODE; ingests made again there).
# usage (repository root): results/synthetic/rounding_parts/run.sh MODE drone|airplane SEED OUT (the log: OUT.log)
# MODE: critic_float, positives_float, distractors_float or view (runner_rounding.py)
mode=$1; cls=$2; seed=$3; out=$4; shift 4
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
export SYNTHAUG_CACHE=${SYNTHAUG_CACHE:-data/sprite_cache_distractors}
export SYNTHAUG_CACHE_MAX_MB=${SYNTHAUG_CACHE_MAX_MB:-8000}
W=${WORK:-data/runs_$mode}
mkdir -p $W
[ -e $W/fits ] || ln -s ../runs/fits $W/fits   # the same d_HOG fits (the rounding comes after them)
case $cls in
  drone) args=(--class drone --seed-counts "${SEED_COUNT:-100}" --mesh ../shared/data/meshes/quadcopter.glb
               --realism-keep 0.25 --realism-features weak_learners --quantize on --pose-sampling fitted_at_seed
               --shape-variation 0.3 --box-calibration 20 --distractor-ratio 5 --distractor-style soft);;
  airplane) args=(--class airplane --seed-counts "${SEED_COUNT:-12}" --mesh ../shared/data/meshes/twin_prop_airplane.glb
                  --scales 1.25 1.0 0.8 0.64 0.51 0.41 0.33 0.26);;
  *) echo "class: drone or airplane" >&2; exit 2;;
esac
call=(python results/synthetic/rounding_parts/runner_rounding.py "$mode" synthetic --work $W
      --protocol configs/protocol/halmstad_v2.json --detectors adaboost --no-scale-check --no-patches --threads 1
      --synthetic-ratios 20 --fit-distance hog "${args[@]}" --eval-split test --training-seeds "$seed" --out "$out"
      "$@")
s0=$(date +%s)
results/synthetic/stop_after_added_cell.sh "$out.log" "cell done" "${call[@]}"
echo "$cls, $mode, seed $seed: $(( $(date +%s) - s0 )) s" | tee -a "$out.log"
