#!/bin/bash
# issue 16: + 20x synthetic with the real seeds keeping half of the positive weight (--synthetic-share 0.5) on the TEST
# videos (HOG, 3 seeds; by count: run_hog_r20.sh, +0.068). Two processes: SEEDS="0 1" and SEEDS=2, then combine.py.
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --synthetic-ratios 20 --synthetic-share 0.5 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' --fit-distance hog \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --training-seeds ${SEEDS:-0 1 2} \
  --out results/synthetic/drone_v1/hog_share0.5_test_seeds${SEEDS// /}
