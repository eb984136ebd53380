#!/bin/bash
# stop 106: AdaBoost's recipe in float (--quantize off) at 100 drone seeds, calibrated test cells, paired by training
# seed against the recipe itself (8-bit; frame_s102/soft5, frame_s103/new_seeds) and real only (intel_cal_test,
# frame_s101, frame_s103/new_seeds): the same machine kind, so the stored cells repeat bit for bit.
# usage (repository root): results/synthetic/adaboost_distractors/frame_s106/tables.sh
set -e
D=results/synthetic/adaboost_distractors
F=$D/frame_s106/float5 real=adaboost_100_seeds.json
. $D/stored_cells.sh
R=() S=() Q=()
for d in $F/seed*/; do
  d=${d%/}; s=${d##*seed}; fl=$(ls $d | grep synthetic) || continue
  stored_cells $s
  R+=("$real_dir/$real=real only"); Q+=("$recipe_dir/$(ls $recipe_dir | grep soft)=the recipe (8-bit)")
  S+=("$d/$fl=the recipe in float")
done
export PYTHONPATH=.
T="python results/learning_curve/video_diversity/table.py"
$T "${Q[@]}" "${S[@]}" --out $D/frame_s106/float5_vs_recipe.md
$T "${R[@]}" "${S[@]}" --out $D/frame_s106/float5_vs_real.md
# 12 seeds (SEED_COUNT=12 run_frame.sh 5 S float12/seedS --distractor-style soft --quantize off): against stop 104's
# recipe cells of the same training seeds
Q=() S=()
for d in $D/frame_s106/float12/seed*/; do
  d=${d%/}; s=${d##*seed}; fl=$(ls $d | grep synthetic) || continue
  Q+=("$D/frame_s104/seed$s/$(ls $D/frame_s104/seed$s | grep synthetic)=12 real + the recipe (8-bit)")
  S+=("$d/$fl=12 real + the recipe in float")
done
$T "${Q[@]}" "${S[@]}" --out $D/frame_s106/float12_vs_recipe12.md
