#!/bin/bash
# issue 16 under protocol halmstad_v1: HOG, 100 real seeds vs + 5x synthetic (d_HOG fit of each training seed's seed set) vs + 5x perturbed
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --synthetic-ratios 5 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' --fit-distance hog \
  --mesh ../shared/data/meshes/quadcopter.glb --perturb-copies 5 --no-scale-check --out results/synthetic/drone_v1/hog
