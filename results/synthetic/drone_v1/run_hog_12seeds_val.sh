#!/bin/bash
# issue 16's 12-seed result checked on the VALIDATION videos (the 100-seed experiments' two splits disagreed in sign):
# HOG, 12 real seeds vs + 20x synthetic (the same d_HOG fits of each training seed's 12-seed set as run_hog_12seeds.sh),
# training seeds 0 1 2, protocol halmstad_v1's validation frames.
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
D=results/synthetic/drone_v1
COMMON="--class drone --detectors hog --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split val --training-seeds ${SEEDS:-0 1 2}"
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 12 --synthetic-ratios 20 \
  --params 'data/runs/fits/drone_12_seed{seed}_hog.json' --fit-distance hog --out $D/hog_12seeds_val
