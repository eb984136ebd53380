#!/bin/bash
# issue 16 under protocol halmstad_v1: CNN, 100 real seeds vs + 20x synthetic (d_CNN fit of each training seed's seed set, made on the fly) vs + 20x perturbed
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors cnn --seed-counts 100 \
  --synthetic-ratios 20 --fit-distance cnn --mesh ../shared/data/meshes/quadcopter.glb --perturb-copies 20 \
  --no-scale-check --out results/synthetic/drone_v1/cnn
