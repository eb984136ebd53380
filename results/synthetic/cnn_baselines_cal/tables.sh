#!/bin/bash
# stop 109: the CNN's defaults at 100 drone seeds against real only and the two baselines, every cell trained on this
# machine (run.sh), paired by training seed and test-video resample.
# usage (repository root): results/synthetic/cnn_baselines_cal/tables.sh
set -e
C=results/synthetic/cnn_baselines_cal
export PYTHONPATH=.
T="python results/learning_curve/video_diversity/table.py"
real="$C/synthetic/cnn_100_seeds.json=real only"
ours="$C/synthetic/$(ls $C/synthetic | grep synthetic)=+ 20x synthetic (the CNN's defaults)"
pert="$C/baselines/$(ls $C/baselines | grep perturbed)=+ 20x perturbed"
copy="$C/baselines/$(ls $C/baselines | grep copy_paste)=+ 20x copy-paste"
$T "$real" "$pert" "$copy" "$ours" --out $C/vs_real.md
$T "$pert" "$ours" --out $C/ours_vs_perturbed.md
$T "$copy" "$ours" --out $C/ours_vs_copy_paste.md
