#!/usr/bin/env bash
# Issue 16: the CNN (fine-tuned on the real seeds afterwards, the default) at 12 real seeds + 20x synthetic from each
# training seed's own d_HOG fit (data/runs/fits/drone_12_seed{s}_hog.json, the runner's, made for ../drone_v2_ensemble/
# hog_12), protocol halmstad_v2, default (ensemble) box map, test split, 5 training seeds.
# usage (repository root): results/synthetic/cnn_finetune/run12.sh TAG "SEEDS" [runner options...]
# --effects-off none: every fitted effect, as these cells were run before the CNN's default left its blurs out
# (stop 52); pass --effects-off default (or any other value: the last one given wins) for the family's default.
# --background-sampling seed: each synthetic object on its own seed's background, as these cells were run before the
# CNN's default became other seeds' backgrounds (stop 69); the last value given wins.
set -euo pipefail
tag=$1; seeds=$2; shift 2
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors cnn --seed-counts 12 --synthetic-ratios 20 --fit-distance hog \
  --no-scale-check --no-patches --training-seeds $seeds --threads 1 --effects-off none --background-sampling seed "$@" \
  --out "results/synthetic/cnn_finetune/$tag" > "results/synthetic/cnn_finetune/$tag.log" 2>&1
