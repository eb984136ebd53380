#!/bin/bash
# issue 16: the synthetic ratio chosen on the VALIDATION videos: HOG real only vs + 2x and + 5x synthetic (d_HOG fits
# of each training seed's seed set, uniform poses), 3 seeds (20x: run_hog_val.sh).
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --synthetic-ratios 2 5 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split val --training-seeds ${SEEDS:-0 1 2} \
  --out results/synthetic/drone_v1/hog_val_ratios
