#!/bin/bash
# the HOG ratio on the VALIDATION videos (protocol's val frames): real only vs + 20x synthetic, 3 seeds.
# Two of these run at once with the seeds in opposite orders share the cells (the cache's lock: each cell once).
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
SEEDS=${SEEDS:-0 1 2}
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --synthetic-ratios 20 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' --fit-distance hog \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split val --seeds $SEEDS \
  --out results/synthetic/drone_v1/hog_val
