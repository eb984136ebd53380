#!/usr/bin/env bash
# Issue 16, Table 1's "CNN + d_CNN" row under the protocol: each training seed's 100-seed drone set fitted with d_CNN
# (the network trained on that seed set's real patches), every other fit setting as the d_HOG fits the CNN rows use
# (synthaug fit's defaults: CMA-ES, budget 3500, grid start, 5-degree view cache, 96-px sprites, sigma_n <= 0.1).
# usage (repository root): results/synthetic/cnn_dcnn/fit.sh "0 1 2 3 4" [DISTANCE]
#   DISTANCE: cnn (the default) or hog (the d_HOG fits data/runs/fits/drone_100_seed{s}_hog.json of the other rows)
set -euo pipefail
export PYTHONPATH=${PYTHONPATH:-.}
dist=${2:-cnn}
for s in $1; do
  out=data/runs/fits/drone_100_seed${s}_${dist}.json
  [ -f "$out" ] && continue
  PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "seed $s: wall %e s, max RSS %M kB" \
    synthaug fit --seed-set data/runs/ingest_drone_seed${s}/seedsets/drone_100 --mesh quadcopter --distance "$dist" \
    --seed 0 --workers 1 --no-progress --out "$out"
done
# then the CNN cells (validation first, then test; the trained detectors are shared):
#   R=results/synthetic/run_100.sh; P='data/runs/fits/drone_100_seed{seed}_cnn.json'
#   $R cnn results/synthetic/cnn_dcnn/val val "0 1 2 3 4" --params "$P"
#   $R cnn results/synthetic/cnn_dcnn/test test "0 1 2 3 4" --params "$P"
