#!/bin/bash
# issue 16 on the VALIDATION videos: CNN real only vs + 20x synthetic by count (d_CNN fits of each training seed's seed
# set, data/runs/fits/drone_100_seed{seed}_cnn.json, made on the fly when missing), 3 seeds, paired. The real-only
# cells are those of the CNN's validation learning-curve cells (cached).
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors cnn --seed-counts 100 \
  --synthetic-ratios 20 --fit-distance cnn --mesh ../shared/data/meshes/quadcopter.glb \
  --no-scale-check --no-patches --eval-split val --training-seeds ${SEEDS:-0 1 2} \
  --out results/synthetic/drone_v1/cnn_val
