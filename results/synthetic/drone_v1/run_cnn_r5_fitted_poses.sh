#!/bin/bash
# issue 16 under protocol halmstad_v1: CNN, 100 real seeds + 5x synthetic with poses drawn around each seed's fitted pose (the same d_CNN fits as run_cnn.sh)
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors cnn --seed-counts 100 \
  --synthetic-ratios 5 --pose-sampling fitted --fit-distance cnn --mesh ../shared/data/meshes/quadcopter.glb \
  --no-scale-check --out results/synthetic/drone_v1/cnn_r5_fitted_poses
