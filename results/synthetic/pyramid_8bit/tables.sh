#!/bin/bash
# stop 106: the 8-bit pyramid's cells (run.sh) against the stored float-pyramid cells of the same calls
# (../airplane_v2/adaboost_recipe/twelve_s*: 12 real and the recipe), paired by training seed; trains nothing.
# usage (repository root): results/synthetic/pyramid_8bit/tables.sh
set -e
P=results/synthetic/pyramid_8bit A=results/synthetic/airplane_v2/adaboost_recipe
T="python results/learning_curve/video_diversity/table.py"
R=() R8=() S=() S8=()
for d in $P/twelve_s*/; do
  d=${d%/}; s=${d##*_s}
  [ -f $d/adaboost_12_seeds.json ] || continue
  syn=$(ls $d | grep synthetic) || continue
  R+=("$A/twelve_s$s/adaboost_12_seeds.json=12 real"); R8+=("$d/adaboost_12_seeds.json=12 real, 8-bit pyramid")
  S+=("$A/twelve_s$s/$(ls $A/twelve_s$s | grep synthetic)=12 real + 20x the recipe")
  S8+=("$d/$syn=12 real + 20x the recipe, 8-bit pyramid")
done
export PYTHONPATH=.
$T "${R[@]}" "${R8[@]}" --out $P/real12.md
$T "${S[@]}" "${S8[@]}" --out $P/recipe12.md
$T "${R8[@]}" "${S8[@]}" --out $P/recipe12_vs_real12.md
