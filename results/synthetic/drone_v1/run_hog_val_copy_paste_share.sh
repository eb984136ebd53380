#!/bin/bash
# issue 16: the copy-paste baseline with the real seeds keeping half of the positive class's weight, on the
# VALIDATION videos (HOG, + 20x copy-paste, --synthetic-share 0.5), 3 seeds: the baseline for run_hog_val_share.sh.
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --copy-paste-ratios 20 --synthetic-share ${SHARE:-0.5} --params 'data/runs/fits/drone_100_seed{seed}_hog.json' \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split val --training-seeds ${SEEDS:-0 1 2} \
  --out results/synthetic/drone_v1/hog_val_copy_paste_share${SHARE:-0.5}
