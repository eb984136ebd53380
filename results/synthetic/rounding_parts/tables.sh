#!/bin/bash
# stop 107: AdaBoost's recipe with its rounding moved or split (run.sh MODE ...), calibrated test cells, paired by
# training seed against the stored cells of the same machine kind: the recipe (8-bit), the recipe in float and real
# only. Airplanes, 12 seeds: ../airplane_v2/adaboost_recipe (twelve_s*, float12_s*); drones, 100 seeds:
# ../adaboost_distractors (frame_s102/soft5 and frame_s103/new_seeds: 8-bit; frame_s106/float5: float; intel_cal_test,
# frame_s101, frame_s103/new_seeds: real only).
# usage (repository root): results/synthetic/rounding_parts/tables.sh
set -e
P=results/synthetic/rounding_parts A=results/synthetic/airplane_v2/adaboost_recipe
D=results/synthetic/adaboost_distractors
export PYTHONPATH=.
T="python results/learning_curve/video_diversity/table.py"
. $D/stored_cells.sh
syn() { echo "$1/$(ls $1 | grep synthetic)"; }
tables() {  # NAME BASE: the array M (the mode's cells) against Q (the 8-bit recipe), F (float) and O (the former
  # defaults; each where every seed has one) and R (real only), paired by training seed, to
  # NAME_vs_{recipe,float,former,real}BASE.md
  [ ${#M[@]} -gt 0 ] || return 0
  $T "${Q[@]}" "${M[@]}" --out $P/$1_vs_recipe$2.md
  [ ${#F[@]} -ne ${#M[@]} ] || $T "${F[@]}" "${M[@]}" --out $P/$1_vs_float$2.md
  [ ${#O[@]} -ne ${#M[@]} ] || $T "${O[@]}" "${M[@]}" --out $P/$1_vs_former$2.md
  $T "${R[@]}" "${M[@]}" --out $P/$1_vs_real$2.md
}
by_size() {  # MODE OUT: the array B, the recipe (8-bit) against MODE by the object's size
  [ ${#B[@]} -eq 0 ] || python results/synthetic/quantize_scale/by_size.py "--names=8-bit,$1" "${B[@]}" > $P/$2
}
gap_table() {  # CLASS OUT: the share of the 12 -> 100 real-seed gap the view rule closes (few, added, many: the
  # comma-separated cells, paired by position)
  if [ -n "$many" ]; then
    python results/synthetic/gap_closed.py --few "$few" --added "$added" --many "$many" \
      --title "AdaBoost, $1, 12 -> 100 real seeds, the recipe rounded where seen near scale 1" --out $P/$2
  fi
}
declare -A LABEL
LABEL[critic_float]="the critic on float draws, the kept rounded"
LABEL[positives_float]="positives in float, distractors 8-bit"
LABEL[distractors_float]="distractors in float, positives 8-bit"
LABEL[view]="rounded where seen near scale 1"
for mode in critic_float positives_float distractors_float view; do
  label=${LABEL[$mode]}
  B=()  # by the object's size, against the recipe (8-bit)
  R=() Q=() F=() O=() M=()  # airplanes, 12 seeds
  for d in $P/${mode}12/seed*/; do
    [ -d "$d" ] || continue
    d=${d%/}; s=${d##*seed}; [ -n "$(ls $d | grep synthetic)" ] || continue
    M+=("$(syn $d)=12 real + the recipe, $label"); R+=("$A/twelve_s$s/adaboost_12_seeds.json=12 real")
    Q+=("$(syn $A/twelve_s$s)=12 real + the recipe (8-bit)")
    [ -d $A/float12_s$s ] && F+=("$(syn $A/float12_s$s)=12 real + the recipe in float")
    [ -d $A/former12_s$s ] && O+=("$(syn $A/former12_s$s)=12 real + the former defaults (the paper's draws)")
    B+=("airplanes, 12 seeds, seed $s=$(syn $A/twelve_s$s),$(syn $d)")
  done
  tables ${mode}12 12
  R=() Q=() F=() O=() M=()  # drones, 100 seeds
  for d in $P/${mode}100/seed*/; do
    [ -d "$d" ] || continue
    d=${d%/}; s=${d##*seed}; [ -n "$(ls $d | grep synthetic)" ] || continue
    stored_cells $s; q=$recipe_dir/$(ls $recipe_dir | grep soft)
    M+=("$(syn $d)=the recipe, $label"); R+=("$real_dir/adaboost_100_seeds.json=real only")
    Q+=("$q=the recipe (8-bit)"); B+=("drones, 100 seeds, seed $s=$q,$(syn $d)")
    [ -d $D/frame_s106/float5/seed$s ] && F+=("$(syn $D/frame_s106/float5/seed$s)=the recipe in float")
  done
  tables ${mode}100 100
  by_size $mode ${mode}_by_size.md
done
# drones, 12 seeds (SEED_COUNT=12 run.sh view drone S view_drones12/seedS): against stop 104's recipe and 12-real cells
# (../adaboost_distractors/frame_s104) and stop 106's float recipe (frame_s106/float12) of the same training seeds
R=() Q=() F=() O=() M=() B=()
for d in $P/view_drones12/seed*/; do
  [ -d "$d" ] || continue
  d=${d%/}; s=${d##*seed}; [ -n "$(ls $d | grep synthetic)" ] || continue
  [ -d $D/frame_s104/seed$s ] || continue  # seed 4 (stop 109) has no stored 8-bit cell: the gap table below only
  M+=("$(syn $d)=12 real + the recipe, ${LABEL[view]}"); R+=("$D/frame_s104/seed$s/adaboost_12_seeds.json=12 real")
  Q+=("$(syn $D/frame_s104/seed$s)=12 real + the recipe (8-bit)")
  B+=("drones, 12 seeds, seed $s=${Q[-1]%=*},$(syn $d)")
  [ -d $D/frame_s106/float12/seed$s ] && F+=("$(syn $D/frame_s106/float12/seed$s)=12 real + the recipe in float")
done
tables view_drones12 12
by_size view view_drones12_by_size.md
# the share of the airplanes' 12 -> 100 real-seed gap the view rule closes (../airplane_v2/adaboost_recipe/real100_s*)
few="" added="" many=""
for d in $P/view12/seed*/; do
  d=${d%/}; s=${d##*seed}; [ -f $A/real100_s$s/adaboost_100_seeds.json ] || continue
  few+="${few:+,}$A/twelve_s$s/adaboost_12_seeds.json"; added+="${added:+,}$(syn $d)"
  many+="${many:+,}$A/real100_s$s/adaboost_100_seeds.json"
done
gap_table airplanes view12_gap_closed.md
# the share of the drones' 12 -> 100 real-seed gap the view rule closes (stop 108; the 100-seed real-only cells of
# stored_cells.sh, as ../adaboost_distractors/frame_s104/tables.sh pairs the 8-bit recipe)
few="" added="" many=""
for d in $P/view_drones12/seed*/; do
  [ -d "$d" ] || continue
  d=${d%/}; s=${d##*seed}; [ -n "$(ls $d | grep synthetic)" ] || continue
  stored_cells $s
  f=$D/frame_s104/seed$s/adaboost_12_seeds.json; [ -f $f ] || f=$d/adaboost_12_seeds.json  # seed 4: its own call's
  few+="${few:+,}$f"; added+="${added:+,}$(syn $d)"
  many+="${many:+,}$real_dir/adaboost_100_seeds.json"
done
gap_table drones view_drones12_gap_closed.md
