#!/bin/bash
# stop 106: AP by object size, AdaBoost's recipe 8-bit vs float, from the stored cells (trains nothing, ~10 s)
# usage (repository root): results/synthetic/quantize_scale/tables.sh
D=results/synthetic/adaboost_distractors A=results/synthetic/airplane_v2/adaboost_recipe
args=()
for s in 0 1 2; do
  args+=("drones, 100 seeds, seed $s=$D/frame_s102/soft5/seed$s/*soft*.json,$D/frame_s106/float5/seed$s/*soft*.json")
done
for d in $D/frame_s106/float12/seed*/; do
  d=${d%/}; s=${d##*seed}
  args+=("drones, 12 seeds, seed $s=$D/frame_s104/seed$s/*synthetic*.json,$d/*synthetic*.json")
done
for s in 0 1 2; do
  args+=("airplanes, 12 seeds, seed $s=$A/twelve_s$s/*synthetic*.json,$A/float12_s$s/*synthetic*.json")
done
PYTHONPATH=. python results/synthetic/quantize_scale/by_size.py "${args[@]}" \
  > results/synthetic/quantize_scale/by_size.md
