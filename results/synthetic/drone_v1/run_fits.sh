#!/bin/bash
# d_HOG fits of the three training seeds' seed sets (drawn by the runner's cells into data/runs/ingest_drone_seed*)
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
for s in 0 1 2; do
  /usr/bin/time -f "seed $s: %e s" python -m synthaug.cli fit --seeds data/runs/ingest_drone_seed$s/seedsets/drone_100 --mesh ../shared/data/meshes/quadcopter.glb --distance hog --out data/runs/fits/drone_100_seed${s}_hog.json --workers 1 --no-progress
done
