#!/bin/bash
# stop 104: AdaBoost at 12 drone seeds, calibrated test cells: real only and + 20x synthetic drawn by AdaBoost's recipe
# (FAMILY_SYNTHETIC, its default since stop 104: the cells of run_frame.sh's flags), paired by training seed, and the
# share of the 12 -> 100 real-seed gap it closes (the 100-seed real-only cells of stops 101-103, the same machine kind).
# usage (repository root): results/synthetic/adaboost_distractors/frame_s104/tables.sh
set -e
D=results/synthetic/adaboost_distractors
F=$D/frame_s104
. $D/stored_cells.sh
real=adaboost_12_seeds.json real100=adaboost_100_seeds.json
seeds=$(for d in $F/seed*/; do d=${d%/}; echo ${d##*seed}; done | sort -n)
soft=$(ls $F/seed$(echo $seeds | cut -d' ' -f1) | grep synthetic)
R=() S=() few="" added="" many=""
for s in $seeds; do
  R+=("$F/seed$s/$real=12 real"); S+=("$F/seed$s/$soft=12 real + 20x synthetic (AdaBoost's recipe)")
  few+="${few:+,}$F/seed$s/$real"; added+="${added:+,}$F/seed$s/$soft"
  stored_cells $s
  many+="${many:+,}$real_dir/$real100"
done
export PYTHONPATH=.
python results/learning_curve/video_diversity/table.py "${R[@]}" "${S[@]}" --out $F/recipe12_vs_real12.md
python results/synthetic/gap_closed.py --few "$few" --added "$added" --many "$many" \
  --title "AdaBoost, drones, 12 -> 100 real seeds, calibrated (seeds $(echo $seeds))" --out $F/gap_closed.md
