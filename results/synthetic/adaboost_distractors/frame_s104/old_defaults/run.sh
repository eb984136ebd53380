#!/bin/bash
# AdaBoost's former defaults (the paper's draws, share 0.25), 12 seeds, calibrated: the same call as run_frame.sh with
# the paper's drawing options given
seed=$1; out=$2
cd /work/main
export PYTHONPATH=. OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl SYNTHAUG_CACHE=/work/scratch/syncache SYNTHAUG_CACHE_MAX_MB=8000
s0=$(date +%s)
python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
   --detectors adaboost --seed-counts 12 --no-scale-check --no-patches --threads 1 \
   --synthetic-ratios 20 --fit-distance hog --mesh ../shared/data/meshes/quadcopter.glb \
   --pose-sampling uniform --shape-variation 0 --quantize off --realism-keep 1 --distractor-ratio 0 \
   --box-calibration 20 --eval-split test --training-seeds "$seed" --out "$out"
echo "paper draws 12 seed $seed: $(( $(date +%s) - s0 )) s"
