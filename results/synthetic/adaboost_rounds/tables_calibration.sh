#!/bin/bash
# Stop 97: the box calibration's tables for AdaBoost (run_calibration.sh's cells against the same detectors' plain
# cells of stops 91-92: real only ../adaboost_critic/{val,test}_eN, the shape cell ../adaboost_wl_critic/{val,test}_sN).
# Trains nothing (~1 min). usage (repository root): results/synthetic/adaboost_rounds/tables_calibration.sh
O=results/synthetic/adaboost_rounds
T=results/learning_curve/video_diversity/table.py
real=adaboost_100_seeds.json
shape=adaboost_100_seeds_20x_synthetic_hog_quadcopter_fitted_poses_at_the_seeds_offsets_share_0.25_shapes_varied_0.3_8_bit_the_25_least_synthetic_of_4x_drawn_of_each_seed_to_a_weak_learner_critic.json
export PYTHONPATH=${PYTHONPATH:-.}
for sp in test val; do
  cr=(); cs=(); pr=(); psh=()
  for d in $O/cal_${sp}_*/; do
    [ -f $d$real ] && cr+=("$d$real=real only, box calibration")
    [ -f $d$shape ] && cs+=("$d$shape=the shape cell, box calibration")
  done
  [ ${#cr[@]} -gt 0 ] || continue
  for d in results/synthetic/adaboost_critic/${sp}_e[0-9]; do pr+=("$d/$real=real only, box map"); done
  for d in results/synthetic/adaboost_wl_critic/${sp}_s[0-9]; do psh+=("$d/$shape=the shape cell, box map"); done
  python $T "${pr[@]}" "${cr[@]}" --out $O/${sp}_calibration_real_only.md
  python $T "${psh[@]}" "${cs[@]}" --out $O/${sp}_calibration_shape_cell.md
  python $T "${cr[@]}" "${cs[@]}" --out $O/${sp}_calibrated_shape_vs_real.md
done
