#!/usr/bin/env bash
# Stop 65: Table 1's drone HOG and CNN gains, HOG's 12-seed share and both detectors' mesh factor on 10 training
# seeds, each with the protocol's video-bootstrap CI and the CI with the training seeds resampled too (trains nothing;
# repository root).
# usage: results/synthetic/ten_seeds/tables.sh "5 6 7 8 9"   (the seeds of this folder's cells that are done)
set -euo pipefail
R=results/synthetic; D=$R/ten_seeds; M=$R/mesh_factor; T=results/learning_curve/video_diversity/table.py
new=$1
# the CNN, blurs left out (its default), 100 seeds: seeds 0-4 as Table 1 / stop 64, seeds 5-9 this folder
NB=without_boundary_blur_and_motion_blur
SB=cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin_$NB
RO=("$R/cnn_figs/no_blurs/cnn_100_seeds.json=real only")
BI=("$M/cnn_100_builtin/$SB.json=+20x, built-in fits" "$M/cnn_builtin_seed3/$SB.json=+20x, built-in fits"
    "$M/cnn_builtin_seed4/$SB.json=+20x, built-in fits")
if [ -n "$new" ]; then
  RO+=("$D/cnn_seeds5_9/cnn_100_seeds.json=real only"); BI+=("$D/cnn_seeds5_9/$SB.json=+20x, built-in fits")
fi
PYTHONPATH=. python $T "${RO[@]}" "${BI[@]}" --out $D/cnn_vs_real.md
# the CNN's mesh factor on the same seeds: quadcopter.glb fits (seeds 0-2 ../placement/cnn_100, stop 63; 3-4 stop 64;
# 5-9 ../mesh_factor/cnn_glb_seeds5_9, stop 65), against the built-in fits above
SG=cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog_$NB
GL=()
for f in $R/placement/cnn_100 $M/cnn_glb_seed3 $M/cnn_glb_seed4 $M/cnn_glb_seeds5_9; do
  GL+=("$f/$SG.json=+20x, quadcopter.glb fits")
done
if [ -n "$new" ]; then PYTHONPATH=. python $T "${BI[@]}" "${GL[@]}" "${RO[@]}" --out $M/cnn_10seeds_builtin_vs_glb.md; fi
# HOG, 100 seeds, this machine's built-in fits on every seed (stop 64's cells)
bash $M/tables_more_seeds.sh "0 1 2 3 4 5 6 7 8 9"
cp $M/hog_more_seeds_vs_real.md $D/hog_vs_real.md
# HOG's 12-seed share: 12 real and + 20x (seeds 0-4: ../hog_12_share/count, stop 62; 5-9: this folder), 100 real
# (seeds 0-4: ../drone_v2_ensemble/hog_100, stop 46; 5-9: ../mesh_factor/hog_real_seed*)
H=$R/hog_12_share/count; few=$H/hog_12_seeds.json; add=$H/hog_12_seeds_20x_synthetic_hog.json
many=$R/drone_v2_ensemble/hog_100/hog_100_seeds.json
if [ -n "$new" ]; then
  few+=",$D/hog_12_seeds5_9/hog_12_seeds.json"; add+=",$D/hog_12_seeds5_9/hog_12_seeds_20x_synthetic_hog.json"
  for s in $new; do many+=",$M/hog_real_seed$s/hog_100_seeds.json"; done
fi
PYTHONPATH=. python $R/gap_closed.py --few "$few" --added "$add" --many "$many" \
  --title "HOG, drones, 12 seeds + 20x synthetic against 12 and 100 real (stop 65)" --out $D/hog_12_gap.md > /dev/null
