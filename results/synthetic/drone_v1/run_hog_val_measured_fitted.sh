#!/bin/bash
# issue 16: both sharpness reducers together on the VALIDATION videos: HOG real only vs + 20x synthetic from the
# sigma_n-measured d_HOG fits with poses around each seed's fitted pose, 3 seeds.
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --synthetic-ratios 20 --params 'data/runs/fits/drone_100_seed{seed}_hog_measured.json' --pose-sampling fitted \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split val --training-seeds 0 1 2 \
  --out results/synthetic/drone_v1/hog_val_measured_fitted
