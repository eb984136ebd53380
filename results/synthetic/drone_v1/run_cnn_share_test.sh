#!/bin/bash
# issue 16: CNN + 20x synthetic (d_CNN fits) with the real seeds keeping half of the positive weight (--synthetic-share
# 0.5) on the TEST videos, 3 seeds (by count: run_cnn.sh, -0.041). Real only and by count are cached cells of run_cnn.sh.
# Two processes: SEEDS="0 1" and SEEDS=2.
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors cnn --seed-counts 100 \
  --synthetic-ratios 20 --synthetic-share ${SHARE:-0.5} --fit-distance cnn --mesh ../shared/data/meshes/quadcopter.glb \
  --no-scale-check --training-seeds ${SEEDS:-0 1 2} \
  --out results/synthetic/drone_v1/cnn_share${SHARE:-0.5}_test_seeds${SEEDS// /}
