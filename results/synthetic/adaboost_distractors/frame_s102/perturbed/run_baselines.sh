#!/bin/bash
# stop 102: AdaBoost's Table 1 baselines (+20x perturbed, +20x copy-paste with the d_HOG fit's silhouettes) with the
# shape cell's training (share 0.25, the real-positive cascade, mining) and the box calibration; stop before real only
# usage (repository root): results/synthetic/adaboost_distractors/frame_s102/perturbed/run_baselines.sh SEED
# (out and log in /work/scratch/base_seedSEED; stop 102 stopped both seeds once the perturbed cell was done: the
# copy-paste cell, next in the runner, did not fit in the session)
# A cell already cached prints no "cell done" line: stop 103 reran seeds 0-1 (copy-paste only, perturbed cached) and
# stopped each call on its one "seed S: cell done" line with a watcher instead (/work/scratch/watchA.sh there).
seed=$1
cd /work/main
export PYTHONPATH=. OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
export SYNTHAUG_CACHE=/work/scratch/syncache SYNTHAUG_CACHE_MAX_MB=8000
out=/work/scratch/base_seed$seed; log=/work/scratch/base_seed$seed.log
s0=$(date +%s)
cmd="python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
   --detectors adaboost --seed-counts 100 --no-scale-check --no-patches --threads 1 --synthetic-ratios \
   --fit-distance hog --mesh ../shared/data/meshes/quadcopter.glb --perturb-copies 20 --copy-paste-ratios 20 \
   --box-calibration 20 --eval-split test --training-seeds $seed --out $out"
setsid $cmd > $log 2>&1 &
pid=$!
while kill -0 $pid 2>/dev/null; do
  if [ "$(grep -c "seed $seed: cell done" $log)" -ge 2 ]; then sleep 2; kill -- -$pid; break; fi
  sleep 20
done
wait $pid
echo "cells wall $(( $(date +%s) - s0 )) s" >> $log
$cmd --read-only >> $log.ro 2>&1
echo "baselines seed $seed done $(( $(date +%s) - s0 )) s" >> /work/scratch/base_times.txt
