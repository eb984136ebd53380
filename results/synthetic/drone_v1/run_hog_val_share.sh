#!/bin/bash
# issue 16: the real seeds keep half of the positive class's weight (--synthetic-share 0.5) on the VALIDATION
# videos: HOG real only vs + 20x synthetic (d_HOG fits, uniform poses), 3 seeds. By count (no share) the 20x synthetic
# positives hold 95 % of it (run_hog_val.sh: -0.023).
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --synthetic-ratios 20 --synthetic-share ${SHARE:-0.5} --params 'data/runs/fits/drone_100_seed{seed}_hog.json' \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split val --training-seeds ${SEEDS:-0 1 2} \
  --out results/synthetic/drone_v1/hog_val_share${SHARE:-0.5}
