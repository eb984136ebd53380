#!/bin/bash
# stop 105: AdaBoost on the airplanes, 12 seeds, calibrated test cells: real only, + 20x synthetic drawn by AdaBoost's
# recipe (its family default) and by the former defaults (the paper's draws, share 0.25), paired by training seed;
# the share of the 12 -> 100 real-seed gap the recipe closes (the 100-seed real-only cells of real100_s*).
# usage (repository root): results/synthetic/airplane_v2/adaboost_recipe/tables.sh
set -e
A=results/synthetic/airplane_v2/adaboost_recipe
export PYTHONPATH=.
T=results/learning_curve/video_diversity/table.py
seeds=$(for d in $A/twelve_s*/; do d=${d%/}; echo ${d##*_s}; done | sort -n)
R=() S=() few="" added="" many="" gap_seeds=""
for s in $seeds; do
  syn=$(ls $A/twelve_s$s | grep synthetic)
  R+=("$A/twelve_s$s/adaboost_12_seeds.json=12 real"); S+=("$A/twelve_s$s/$syn=12 real + 20x synthetic (AdaBoost's recipe)")
  if [ -f $A/real100_s$s/adaboost_100_seeds.json ]; then
    few+="${few:+,}$A/twelve_s$s/adaboost_12_seeds.json"; added+="${added:+,}$A/twelve_s$s/$syn"
    many+="${many:+,}$A/real100_s$s/adaboost_100_seeds.json"; gap_seeds+=" $s"
  fi
done
python $T "${R[@]}" "${S[@]}" --out $A/recipe12_vs_real12.md
if [ -n "$many" ]; then
  python results/synthetic/gap_closed.py --few "$few" --added "$added" --many "$many" \
    --title "AdaBoost, airplanes, 12 -> 100 real seeds, calibrated (seeds$gap_seeds)" --out $A/gap_closed.md
fi
F=() FR=() FS=()
for d in $A/former12_s*/; do
  d=${d%/}; s=${d##*_s}; syn=$(ls $d | grep synthetic) || continue
  F+=("$d/$syn=12 real + 20x synthetic (former defaults: the paper's draws)")
  FR+=("$A/twelve_s$s/adaboost_12_seeds.json=12 real")
  FS+=("$A/twelve_s$s/$(ls $A/twelve_s$s | grep synthetic)=12 real + 20x synthetic (AdaBoost's recipe)")
done
if [ ${#F[@]} -gt 0 ]; then
  python $T "${FR[@]}" "${F[@]}" --out $A/former12_vs_real12.md
  python $T "${F[@]}" "${FS[@]}" --out $A/recipe12_vs_former12.md
fi
# one factor of the recipe put back to the former defaults' (probes, two seeds): its distractors left out
# (run.sh recipe SEED nodistr12_sSEED --distractor-ratio 0) and its poses uniform, the paper's
# (run.sh recipe SEED uniform12_sSEED --pose-sampling uniform) and the mesh alone, no shape variation
# (run.sh recipe SEED meshalone12_sSEED --shape-variation 0) and float renders (run.sh recipe SEED float12_sSEED
# --quantize off); each against the recipe and the former defaults
probe() {  # TAG LABEL
  local P=() PR=() PF=() d s f
  for d in $A/$1_s*/; do
    [ -d "$d" ] || continue
    d=${d%/}; s=${d##*_s}; syn=$(ls $d | grep synthetic) || continue
    P+=("$d/$syn=12 real + 20x synthetic ($2)")
    PR+=("$A/twelve_s$s/$(ls $A/twelve_s$s | grep synthetic)=12 real + 20x synthetic (AdaBoost's recipe)")
    f=$A/former12_s$s; PF+=("$f/$(ls $f | grep synthetic)=12 real + 20x synthetic (former defaults: the paper's draws)")
  done
  if [ ${#P[@]} -gt 0 ]; then
    python $T "${PR[@]}" "${P[@]}" --out $A/$1_vs_recipe12.md
    python $T "${PF[@]}" "${P[@]}" --out $A/$1_vs_former12.md
  fi
}
probe nodistr12 "the recipe without distractors"
probe uniform12 "the recipe with the paper's poses"
probe meshalone12 "the recipe with the mesh alone"
probe float12 "the recipe in float"
# stops 108-109: 100 seeds, the recipe at native scale (run.sh recipe SEED native100_sSEED, the default) and rounding
# every seed (run.sh recipe SEED eightbit100_sSEED --quantize on), each stopped after its added cell, against the
# stored 100-real cells (real100_sSEED), paired by training seed
N=() E=() R=()
for d in $A/native100_s*/; do
  [ -d "$d" ] || continue
  d=${d%/}; s=${d##*_s}; [ -d $A/eightbit100_s$s ] && [ -f $A/real100_s$s/adaboost_100_seeds.json ] || continue
  R+=("$A/real100_s$s/adaboost_100_seeds.json=100 real")
  E+=("$A/eightbit100_s$s/$(ls $A/eightbit100_s$s | grep synthetic)=100 real + the recipe (8-bit)")
  N+=("$d/$(ls $d | grep synthetic)=100 real + the recipe at native scale")
done
if [ ${#N[@]} -gt 0 ]; then
  python $T "${R[@]}" "${E[@]}" "${N[@]}" --out $A/native100_vs_real100.md
  python $T "${E[@]}" "${N[@]}" --out $A/native100_vs_eightbit100.md
fi
