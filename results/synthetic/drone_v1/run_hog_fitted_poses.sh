#!/bin/bash
# issue 16 under protocol halmstad_v1: HOG, 100 real seeds vs + 5x synthetic with poses drawn around each seed's fitted pose (pose_jitter_deg 20)
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --synthetic-ratios 5 --pose-sampling fitted --params 'data/runs/fits/drone_100_seed{seed}_hog.json' --fit-distance hog \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --out results/synthetic/drone_v1/hog_fitted_poses
