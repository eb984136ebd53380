#!/usr/bin/env bash
# Stop 66: HOG, drones, 100 seeds + 20x synthetic from d_HOG fits made with quadcopter.glb decimated to the built-in
# quadcopter's 888 faces (decimate.py), one training seed after another; the same synthaug fit command as the
# built-in and .glb fits of stop 64 (README), the same run_100.sh cell.
# usage (repository root): results/synthetic/mesh_factor/run_decimated.sh "SEEDS" [TAG MESH]
#   TAG MESH default to glbdec data/meshes/quadcopter_glb_decimated.ply; another mesh written by decimate.py gets a
#   tag of its own (fits data/runs/fits/drone_100_seed{s}_hog_TAG.json, cells hog_TAG_seed{s})
set -euo pipefail
D=results/synthetic/mesh_factor; tag=${2:-glbdec}; mesh=${3:-data/meshes/quadcopter_glb_decimated.ply}
for s in $1; do
  F=data/runs/fits/drone_100_seed${s}_hog_$tag.json
  [ -f "$F" ] || PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 python -m synthaug.cli fit \
    --seeds data/runs/ingest_drone_seed$s/seedsets/drone_100 --mesh "$mesh" \
    --distance hog --out "$F" --workers 1 --no-progress > $D/fit_${tag}_seed$s.log 2>&1
  results/synthetic/run_100.sh hog $D/hog_${tag}_seed$s test $s \
    --params "data/runs/fits/drone_100_seed{seed}_hog_$tag.json"
done
