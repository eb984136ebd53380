#!/bin/bash
# Stop 109 (issue 16's first target for the CNN): the CNN's shipped defaults (its synthetic positives without the
# fitted blurs, on other seeds' backgrounds; the box calibration every 20th frame) at 100 drone seeds, test split,
# against the two baselines the target names, every cell trained on this machine: real only, + 20x synthetic (d_HOG
# fits of each training seed's own seed set, the built-in quadcopter, as Table 1's CNN rows), + 20x perturbed (the
# paper's) and + 20x copy-paste (the same fits' silhouettes). Before this stop the baselines were measured only under
# the box map (stop 52, ../cnn_finetune/test_baselines), not under the calibration that became the default at stop 73.
# Two calls side by side on the 2 cores; both end with the real-only cells, which the cell cache trains once.
# usage (repository root): results/synthetic/cnn_baselines_cal/run.sh synthetic|baselines "SEEDS" OUT [--read-only]
part=$1; seeds=$2; out=$3; shift 3
case $part in
  synthetic) add=(--synthetic-ratios 20);;
  baselines) add=(--synthetic-ratios --perturb-copies 20 --copy-paste-ratios 20);;
  *) echo "part: synthetic or baselines" >&2; exit 2;;
esac
export PYTHONPATH=${PYTHONPATH:-.} OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
s0=$(date +%s)
python -m synthaug.evaluate.runner synthetic --protocol configs/protocol/halmstad_v2.json --class drone \
  --detectors cnn --seed-counts 100 --fit-distance hog "${add[@]}" --no-scale-check --no-patches --threads 1 \
  --eval-split test --training-seeds $seeds --out "$out" "$@"
echo "cnn $part seeds $seeds $*: $(( $(date +%s) - s0 )) s"
