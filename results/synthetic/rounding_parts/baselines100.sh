#!/bin/bash
# stop 109 (issue 16's first target for AdaBoost's default): the drones at 100 seeds, seeds 0-2, AdaBoost's default
# since stop 108 (the recipe rounded at native scale: view100/) against the stored real-only, + 20x perturbed and
# + 20x copy-paste cells of the same seeds and machine kind (../adaboost_distractors, stops 101-103), each paired by
# training seed and test-video resample, to view100_vs_baselines.md.
# usage (repository root): results/synthetic/rounding_parts/baselines100.sh
set -e
P=results/synthetic/rounding_parts D=results/synthetic/adaboost_distractors
export PYTHONPATH=.
. $D/stored_cells.sh
real=() pert=() copy=() native=()
for s in 0 1 2; do
  stored_cells $s
  real+=("$real_dir/adaboost_100_seeds.json=real only")
  pert+=("$(ls $D/frame_s102/perturbed/seed$s/*perturbed*.json \
             $D/frame_s103/baselines/seed$s/*perturbed*.json 2>/dev/null | head -1)=+ 20x perturbed")  # 0-1, 2
  copy+=("$(ls $D/frame_s103/baselines/seed$s/*copy_paste*.json)=+ 20x copy-paste")
  name="+ 20x the recipe rounded at native scale (AdaBoost's default since stop 108)"
  native+=("$(ls $P/view100/seed$s/*.json)=$name")
done
out=$P/view100_vs_baselines.md
: > $out
for base in real pert copy; do
  declare -n B=$base
  python results/learning_curve/video_diversity/table.py "${B[@]}" "${native[@]}" --out /tmp/baselines100_$base.md
  cat /tmp/baselines100_$base.md >> $out; echo >> $out
done
