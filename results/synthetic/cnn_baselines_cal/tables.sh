#!/bin/bash
# stop 109: the CNN's defaults at 100 drone seeds against real only and the two baselines, every cell trained on this
# machine (run.sh), paired by training seed and test-video resample. Seeds 0-2: synthetic/ and baselines/; seed 3
# (real only, ours and copy-paste): seed3/ (run.sh synthetic "3" seed3 --copy-paste-ratios 20); its perturbed cell:
# seed3_baselines/ (run.sh baselines "3" seed3_baselines; its copy-paste and real-only cells read back from the cache).
# usage (repository root): results/synthetic/cnn_baselines_cal/tables.sh
set -e
C=results/synthetic/cnn_baselines_cal
export PYTHONPATH=.
T="python results/learning_curve/video_diversity/table.py"
real=() ours=() copy=()
for d in $C/synthetic $C/seed3; do
  [ -f $d/cnn_100_seeds.json ] || continue
  real+=("$d/cnn_100_seeds.json=real only")
  ours+=("$d/$(ls $d | grep synthetic)=+ 20x synthetic (the CNN's defaults)")
done
for d in $C/baselines $C/seed3; do
  f=$(ls $d 2>/dev/null | grep copy_paste) || continue
  copy+=("$d/$f=+ 20x copy-paste")
done
pert=()
for d in $C/baselines $C/seed3_baselines; do
  f=$(ls $d 2>/dev/null | grep perturbed) || continue
  pert+=("$d/$f=+ 20x perturbed")
done
$T "${real[@]}" "${pert[@]}" "${copy[@]}" "${ours[@]}" --out $C/vs_real.md
$T "${pert[@]}" "${ours[@]}" --out $C/ours_vs_perturbed.md
$T "${copy[@]}" "${ours[@]}" --out $C/ours_vs_copy_paste.md
