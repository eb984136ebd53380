#!/usr/bin/env bash
# Issue 15: what keeps HOG from gaining with all the labelled training frames? Validation split, ridge box map.
# usage (from the repository root): results/learning_curve/drone_all_frames_val/run.sh TAG [runner options...]
#   e.g. run.sh stride30_all --seed-counts --all-frames
#        run.sh ap_all --seed-counts --all-frames --mining-select ap
# writes results/learning_curve/drone_all_frames_val/val_TAG/ (the cells are cached in data/runs/cells)
set -euo pipefail
tag=$1; shift
PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, max RSS %M kB" \
  python -m synthaug.evaluate.runner learning-curve --class drone --detectors hog "$@" \
  --eval-split val --box-model ridge --no-scale-check --no-patches \
  --training-seeds 0 1 2 --threads 1 --out "results/learning_curve/drone_all_frames_val/val_$tag"
