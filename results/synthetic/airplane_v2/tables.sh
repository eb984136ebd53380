#!/usr/bin/env bash
# Every airplane table of README.md from the cell cache (data/runs/cells: trains nothing when the cells are there),
# then the paired tables between added-positive conditions. Repository root: bash results/synthetic/airplane_v2/tables.sh
set -euo pipefail
export LOG_SUFFIX=_tables   # the training logs (wall times) stay as they are
A=results/synthetic/airplane_v2; R=$A/run.sh; T=results/learning_curve/video_diversity/table.py
JET=../shared/data/meshes/jet_airliner.ply
$R hog hog_100 "0 1 2" --perturb-copies 20 --copy-paste-ratios 20
$R cnn cnn_100 "0 1 2" --perturb-copies 20 --copy-paste-ratios 20
$R hog hog_100_jet "0 1 2" --mesh $JET
$R hog hog_100_fitted_poses "0 1 2" --pose-sampling fitted
$R cnn cnn_100_fitted_poses "0 1 2" --pose-sampling fitted
$R hog hog_12 "0 1 2" --seed-counts 12
$R hog hog_12_fitted_poses "0 1 2" --seed-counts 12 --pose-sampling fitted
$R cnn cnn_12 "0 1 2" --seed-counts 12
$R hog hog_100_val "0 1 2" --pose-sampling uniform fitted --eval-split val
$R cnn cnn_100_val "0 1 2" --pose-sampling uniform fitted --eval-split val
$R hog hog_100_5seeds "0 1 2 3 4" --pose-sampling uniform fitted
$R cnn cnn_100_5seeds "0 1 2 3 4"
SYN=20x_synthetic_hog_twin_prop_airplane; FIT=20x_synthetic_hog_twin_prop_airplane_fitted_poses
CP=20x_copy_paste_hog_twin_prop_airplane_silhouettes
for d in hog cnn; do
  S=$A/${d}_100
  PYTHONPATH=. python $T "$S/${d}_100_seeds_20x_perturbed.json=+20x perturbed" "$S/${d}_100_seeds_$SYN.json=+20x synthetic" \
    --out $S/synthetic_vs_perturbed.md > /dev/null
  PYTHONPATH=. python $T "$S/${d}_100_seeds_$CP.json=+20x copy-paste" "$S/${d}_100_seeds_$SYN.json=+20x synthetic" \
    --out $S/synthetic_vs_copy_paste.md > /dev/null
  PYTHONPATH=. python $T "$S/${d}_100_seeds_$SYN.json=+20x synthetic, uniform poses" \
    "$A/${d}_100_fitted_poses/${d}_100_seeds_$FIT.json=+20x synthetic, fitted poses" --out $A/${d}_100_fitted_poses/fitted_vs_uniform.md > /dev/null
  PYTHONPATH=. python $T "$S/${d}_100_seeds_20x_perturbed.json=+20x perturbed" \
    "$A/${d}_100_fitted_poses/${d}_100_seeds_$FIT.json=+20x synthetic, fitted poses" --out $A/${d}_100_fitted_poses/fitted_vs_perturbed.md > /dev/null
  PYTHONPATH=. python $T "$S/${d}_100_seeds_$CP.json=+20x copy-paste" \
    "$A/${d}_100_fitted_poses/${d}_100_seeds_$FIT.json=+20x synthetic, fitted poses" --out $A/${d}_100_fitted_poses/fitted_vs_copy_paste.md > /dev/null
  PYTHONPATH=. python results/synthetic/gap_closed.py --few $A/${d}_12/${d}_12_seeds.json \
    --added $A/${d}_12/${d}_12_seeds_$SYN.json --many $S/${d}_100_seeds.json --out $A/${d}_12/gap_closed.md > /dev/null
done
PYTHONPATH=. python $T "$A/hog_100/hog_100_seeds_$SYN.json=+20x synthetic, twin_prop_airplane.glb" \
  "$A/hog_100_jet/hog_100_seeds_20x_synthetic_hog_jet_airliner.json=+20x synthetic, jet_airliner.ply" --out $A/hog_100_jet/jet_vs_twin.md > /dev/null
PYTHONPATH=. python results/synthetic/gap_closed.py --few $A/hog_12/hog_12_seeds.json \
  --added $A/hog_12_fitted_poses/hog_12_seeds_$FIT.json --many $A/hog_100/hog_100_seeds.json --out $A/hog_12_fitted_poses/gap_closed.md > /dev/null
for d in hog_100_val cnn_100_val hog_100_5seeds; do
  k=${d%%_*}
  PYTHONPATH=. python $T "$A/$d/${k}_100_seeds_$SYN.json=uniform poses" "$A/$d/${k}_100_seeds_$FIT.json=fitted poses" \
    --out $A/$d/fitted_vs_uniform.md > /dev/null
done
