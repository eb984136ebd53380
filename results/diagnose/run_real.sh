#!/bin/bash
# issue 20: the real drone and airplane reports rerun with the current diagnosis (calibrated floors, tone evidence,
# the gray cut of the colour-only candidates). Seed sets as in the README's session-3 ingest (colour, neighbour
# frames), the committed HOG fits of Table 1.
set -e
cd "$(dirname "$0")/../.."
export OMP_NUM_THREADS=1
if [[ ! -f data/halmstad/seedsets/airplane_100/seedset.json ]]; then
  /usr/bin/time -f "ingest: wall %e s" synthaug ingest --videos ../shared/data/halmstad/videos --labels ../shared/data/halmstad/labels \
      --split configs/splits/halmstad.json --out data/halmstad --seed-counts 100 --workers 1 --no-progress
fi
/usr/bin/time -f "drone: wall %e s" synthaug diagnose --seed-set data/halmstad/seedsets/drone_100 --mesh ../shared/data/meshes/quadcopter.glb \
    --params results/paper/fits/drone_100_hog.json --distance hog --out results/diagnose/drone_100 --no-progress
/usr/bin/time -f "airplane: wall %e s" synthaug diagnose --seed-set data/halmstad/seedsets/airplane_100 --mesh ../shared/data/meshes/twin_prop_airplane.glb \
    --params results/paper/fits/airplane_100_hog.json --distance hog --out results/diagnose/airplane_100 --no-progress
