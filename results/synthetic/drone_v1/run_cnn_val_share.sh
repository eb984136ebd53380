#!/bin/bash
# issue 16: the CNN's real seeds keep half of the positive class's weight (--synthetic-share 0.5: per-positive weights in
# the BCE loss) on the VALIDATION videos: CNN real only vs + 20x synthetic (d_CNN fits of each training seed's seed set,
# data/runs/fits/drone_100_seed{seed}_cnn.json, made on the fly when missing), 3 seeds, paired. By count (no share) the
# 20x synthetic positives hold 95 % of it (run_cnn_val.sh). The real-only cells are cached (the CNN's validation cells).
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors cnn --seed-counts 100 \
  --synthetic-ratios 20 --synthetic-share ${SHARE:-0.5} --fit-distance cnn --mesh ../shared/data/meshes/quadcopter.glb \
  --no-scale-check --no-patches --eval-split val --training-seeds ${SEEDS:-0 1 2} \
  --out results/synthetic/drone_v1/cnn_val_share${SHARE:-0.5}
