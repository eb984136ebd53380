#!/bin/bash
# issue 16's 12-seed comparison for the CNN: 12 real seeds vs + 20x synthetic from d_CNN fits of each training seed's
# own 12-seed set (made by the runner when missing), test split, training seeds ${SEEDS:-0 1 2}.
# Two at once share the cells (the cache's lock): SEEDS="0 1" and SEEDS=2.
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
D=results/synthetic/drone_v1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors cnn \
  --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split test \
  --training-seeds ${SEEDS:-0 1 2} --seed-counts 12 --synthetic-ratios 20 \
  --params 'data/runs/fits/drone_12_seed{seed}_cnn.json' --fit-distance cnn --out $D/cnn_12seeds${TAG:-}
