#!/usr/bin/env bash
# Issue 16 factor ablations on the drones: 100 real seeds + 20x synthetic (d_HOG fits of each training seed's 100-seed
# set, data/runs/fits/drone_100_seed{s}_hog.json), protocol halmstad_v2, defaults (ensemble box map; the CNN fine-tuned
# on the real seeds afterwards), plus the runner options that set the factor.
# usage (repository root): results/synthetic/run_100.sh DETECTOR OUT SPLIT "SEEDS" [runner options...]
#   run_100.sh cnn results/synthetic/shape_variation/cnn_test test "0 1 2 3 4" --shape-variation 0.3
#   (writes OUT/ and OUT.log)
# --effects-off none: every fitted effect, as these cells were run before the CNN's default left its blurs out
# (stop 52); pass --effects-off default (or any other value: the last one given wins) for the family's default.
# --ada-cascade all: AdaBoost's soft cascade from every training positive, as these cells were run before the
# real-positive cascade became the default (stop 60); the last value given wins.
# --synthetic-share count: every positive weighs the same, as these cells were run before AdaBoost's default share
# of 0.25 (stop 61); --synthetic-share 0.25 (or any other value given after it) wins.
# --background-sampling seed: each synthetic object on its own seed's background, as these cells were run before the
# CNN's default became other seeds' backgrounds (stop 69); --background-sampling default (or other) given after wins.
# The fits' mesh is whatever made data/runs/fits/drone_100_seed{s}_hog.json: Table 1's HOG and CNN rows used fits the
# runner made (the built-in quadcopter); the AdaBoost rows of stops 61-63 used fits made with quadcopter.glb
# (../adaboost_100_share/README.md). The mesh alone moves HOG by +0.049 (../mesh_factor/): pass --params to choose.
set -euo pipefail
det=$1; out=$2; split=$3; seeds=$4; shift 4
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors "$det" --seed-counts 100 --synthetic-ratios 20 --params 'data/runs/fits/drone_100_seed{seed}_hog.json' \
  --no-scale-check --no-patches --eval-split "$split" --training-seeds $seeds --threads 1 --effects-off none \
  --ada-cascade all --synthetic-share count --background-sampling seed "$@" \
  --out "$out" > "$out.log" 2>&1
