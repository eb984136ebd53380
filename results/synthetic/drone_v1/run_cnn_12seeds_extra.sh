#!/bin/bash
# the CNN's 12-seed comparison completed: (c) 100 real seeds recomputed on this machine (the gap's other end, test),
# and the 12-seed comparison on the validation videos. STEP=c|val
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
D=results/synthetic/drone_v1
COMMON="--class drone --detectors cnn --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --training-seeds ${SEEDS:-0 1 2}"
if [[ ${STEP:-c} == c ]]; then
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --eval-split test --seed-counts 100 --out $D/cnn_12seeds_real100
else
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --eval-split val --seed-counts 12 --synthetic-ratios 20 \
    --params 'data/runs/fits/drone_12_seed{seed}_cnn.json' --fit-distance cnn --out $D/cnn_12seeds_val
fi
