#!/usr/bin/env bash
# Stop 65: the CNN (blurs left out), built-in fits against quadcopter.glb fits and real only, training seeds 0-9
# (trains nothing; repository root). Seeds 0-2: stop 63's cells (one machine); 3-4: stop 64's; 5-9: stop 65's.
set -euo pipefail
R=results/synthetic; D=$R/mesh_factor; T=results/learning_curve/video_diversity/table.py
NB=without_boundary_blur_and_motion_blur
SB=cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin_$NB
SG=cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog_$NB
BI=(); GL=()
for f in $D/cnn_100_builtin $D/cnn_builtin_seed3 $D/cnn_builtin_seed4 $R/ten_seeds/cnn_seeds5_9; do
  BI+=("$f/$SB.json=+20x, built-in fits")
done
for f in $R/placement/cnn_100 $D/cnn_glb_seed3 $D/cnn_glb_seed4 $D/cnn_glb_seeds5_9; do
  GL+=("$f/$SG.json=+20x, quadcopter.glb fits")
done
RO=("$R/cnn_figs/no_blurs/cnn_100_seeds.json=real only" "$R/ten_seeds/cnn_seeds5_9/cnn_100_seeds.json=real only")
PYTHONPATH=. python $T "${BI[@]}" "${GL[@]}" "${RO[@]}" --out $D/cnn_10seeds_builtin_vs_glb.md
