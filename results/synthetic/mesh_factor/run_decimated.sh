#!/usr/bin/env bash
# Stop 66: HOG, drones, 100 seeds + 20x synthetic from d_HOG fits made with quadcopter.glb decimated to the built-in
# quadcopter's 888 faces (decimate.py), one training seed after another; the same synthaug fit command as the
# built-in and .glb fits of stop 64 (README), the same run_100.sh cell.
# usage (repository root): results/synthetic/mesh_factor/run_decimated.sh "SEEDS"
set -euo pipefail
D=results/synthetic/mesh_factor
for s in $1; do
  F=data/runs/fits/drone_100_seed${s}_hog_glbdec.json
  [ -f "$F" ] || PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 python -m synthaug.cli fit \
    --seeds data/runs/ingest_drone_seed$s/seedsets/drone_100 --mesh data/meshes/quadcopter_glb_decimated.ply \
    --distance hog --out "$F" --workers 1 --no-progress > $D/fit_glbdec_seed$s.log 2>&1
  results/synthetic/run_100.sh hog $D/hog_glbdec_seed$s test $s \
    --params 'data/runs/fits/drone_100_seed{seed}_hog_glbdec.json'
done
