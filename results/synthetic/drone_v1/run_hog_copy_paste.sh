#!/bin/bash
# issue 16, item 4: the copy-paste baseline on the TEST videos: HOG + 20x copy-paste (each seed's object cut out with
# its d_HOG fit's silhouette, pasted on other seeds' backgrounds), 3 seeds, beside + 20x synthetic (run_hog_r20.sh).
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
  --copy-paste-ratios 20 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --training-seeds ${SEEDS:-0 1 2} \
  --out results/synthetic/drone_v1/hog_copy_paste
