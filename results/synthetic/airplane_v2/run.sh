#!/usr/bin/env bash
# Issue 16: the airplane class's table under protocol halmstad_v2 (default ensemble box map): real only, + 20x synthetic
# (a d_HOG fit of each training seed's own 100-seed set with the shared twin_prop_airplane.glb, made by the runner),
# + 20x perturbed, + 20x copy-paste; the pyramid extended to 0.26 for the large airplanes (as results/paper/).
# usage (repository root): results/synthetic/airplane_v2/run.sh DETECTOR TAG "SEEDS" [runner options...]
#   run.sh hog hog_100 "0 1 2" --perturb-copies 20 --copy-paste-ratios 20
# --effects-off none: every fitted effect, as these cells were run before the CNN's default left its blurs out
# (stop 52); pass --effects-off default (or any other value: the last one given wins) for the family's default.
# --ada-cascade all: AdaBoost's soft cascade from every training positive, as these cells were run before the
# real-positive cascade became the default (stop 60); the last value given wins.
# --synthetic-share count: every positive weighs the same, as these cells were run before AdaBoost's default share
# of 0.25 (stop 61); --synthetic-share 0.25 (or any other value given after it) wins.
# --background-sampling seed: each synthetic object on its own seed's background, as these cells were run before the
# CNN's default became other seeds' backgrounds (stop 69); the last value given wins.
set -euo pipefail
det=$1; tag=$2; seeds=$3; shift 3
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class airplane \
  --detectors "$det" --seed-counts 100 --synthetic-ratios 20 --fit-distance hog \
  --mesh ../shared/data/meshes/twin_prop_airplane.glb --scales 1.25 1.0 0.8 0.64 0.51 0.41 0.33 0.26 \
  --no-scale-check --no-patches --training-seeds $seeds --threads 1 --effects-off none --ada-cascade all \
  --synthetic-share count --background-sampling seed "$@" \
  --out "results/synthetic/airplane_v2/$tag" > "results/synthetic/airplane_v2/$tag${LOG_SUFFIX:-}.log" 2>&1
