#!/bin/bash
# issue 16, object noise measured instead of fitted: d_HOG fits with FitConfig(object_noise="measured")
# (σ_n of each seed = its patch's noise level) for the three training seeds' seed sets, then HOG real only
# vs + 20x synthetic from those fits on the validation videos and on the test videos (3 seeds, protocol halmstad_v1).
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
for s in 0 1 2; do
  f=data/runs/fits/drone_100_seed${s}_hog_measured.json
  [ -f $f ] || /usr/bin/time -f "fit seed $s: %e s" python -m synthaug.cli fit --seed-set data/runs/ingest_drone_seed$s/seedsets/drone_100 \
    --mesh ../shared/data/meshes/quadcopter.glb --distance hog --object-noise measured --out $f --workers 1 --no-progress
done
for split in val test; do
  /usr/bin/time -f "$split: wall %e s" python -m synthaug.evaluate.runner synthetic --class drone --detectors hog --seed-counts 100 \
    --synthetic-ratios 20 --params 'data/runs/fits/drone_100_seed{seed}_hog_measured.json' \
    --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split $split --training-seeds 0 1 2 \
    --out results/synthetic/drone_v1/hog_measured_noise_$split
done
