#!/usr/bin/env bash
# Stop 67: the background factor's tables (trains nothing; repository root). HOG, drones, 100 seeds (training seeds 0-4
# hog_a, 5-9 hog_b, every cell from this machine's built-in fits), and on the validation videos; HOG at 12 seeds
# (seeds 5-9, hog_12_b, the 12-seed fits of ../ten_seeds/hog_12_seeds5_9 read back; stop 68: seeds 0-4 too) with its
# share of the 12 -> 100 gap; the CNN (seeds cnn_* given).
# usage: results/synthetic/background/tables.sh ["CNN OUT FOLDERS"]
set -euo pipefail
R=results/synthetic; D=$R/background; T=results/learning_curve/video_diversity/table.py
S=hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin; O=_backgrounds_of_other_seeds
C=cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin_without_boundary_blur_and_motion_blur  # the CNN's
# three_way "FOLDERS" REAL_FILE SYNTHETIC_STEM REAL_LABEL OUT: the real-only, own- and other-background results of
# every folder, tabled against real only (OUT_vs_real.md) and other against own (OUT_other_vs_own.md)
three_way() {
  local folders=($1) f; local rows=()
  for f in "${folders[@]}"; do rows+=("$f/$2=$4"); done
  for f in "${folders[@]}"; do rows+=("$f/$3.json=+20x synthetic, own backgrounds"); done
  for f in "${folders[@]}"; do rows+=("$f/$3$O.json=+20x synthetic, other seeds' backgrounds"); done
  PYTHONPATH=. python $T "${rows[@]}" --out "${5}_vs_real.md"
  PYTHONPATH=. python $T "${rows[@]:${#folders[@]}}" --out "${5}_other_vs_own.md"
}
three_way "$D/hog_a $D/hog_b" hog_100_seeds.json $S "real only" $D/hog_100
# the same on the validation videos: seeds 0-2 hog_val_a, 3-4 hog_val_b (stop 67); 5-7 hog_val_c, 8-9 hog_val_d
# (stop 68, every detector read back)
three_way "$D/hog_val_a $D/hog_val_b" hog_100_seeds.json $S "real only" $D/hog_100_val
three_way "$D/hog_val_a $D/hog_val_b $D/hog_val_c $D/hog_val_d" hog_100_seeds.json $S "real only" $D/hog_100_val10
# 12 seeds: 12 real and + 20x own backgrounds are ../ten_seeds/hog_12_seeds5_9's cells (the same fits); 100 real
# ../mesh_factor/hog_real_seed{5..9}
H=$R/ten_seeds/hog_12_seeds5_9; B=$D/hog_12_b
PYTHONPATH=. python $T "$H/hog_12_seeds_20x_synthetic_hog.json=+20x synthetic, own backgrounds" \
  "$B/hog_12_seeds_20x_synthetic_hog$O.json=+20x synthetic, other seeds' backgrounds" \
  "$H/hog_12_seeds.json=12 real only" \
  --out $D/hog_12_other_vs_own.md
many=""; for s in 5 6 7 8 9; do many+="${many:+,}$R/mesh_factor/hog_real_seed$s/hog_100_seeds.json"; done
for tag in own other; do
  add=$H/hog_12_seeds_20x_synthetic_hog.json; [ $tag = other ] && add=$B/hog_12_seeds_20x_synthetic_hog$O.json
  PYTHONPATH=. python $R/gap_closed.py --few "$H/hog_12_seeds.json" --added "$add" --many "$many" \
    --title "HOG, drones, seeds 5-9, 12 seeds + 20x synthetic ($tag backgrounds) against 12 and 100 real (stop 67)" \
    --out $D/hog_12_gap_$tag.md > /dev/null
done
# stop 68: 12 seeds on training seeds 0-9. Seeds 0-4: ../hog_12_share/bg12 (12 real, own and other backgrounds, from
# fits made again on this machine); seeds 5-9 as above; 100 real: seeds 0-4 ../drone_v2_ensemble/hog_100 (stop 46)
B12=$R/hog_12_share/bg12
PYTHONPATH=. python $T "$B12/hog_12_seeds_20x_synthetic_hog.json=+20x synthetic, own backgrounds" \
  "$H/hog_12_seeds_20x_synthetic_hog.json=+20x synthetic, own backgrounds" \
  "$B12/hog_12_seeds_20x_synthetic_hog$O.json=+20x synthetic, other seeds' backgrounds" \
  "$B/hog_12_seeds_20x_synthetic_hog$O.json=+20x synthetic, other seeds' backgrounds" \
  "$B12/hog_12_seeds.json=12 real only" "$H/hog_12_seeds.json=12 real only" --out $D/hog_12_10seeds_other_vs_own.md
many=$R/drone_v2_ensemble/hog_100/hog_100_seeds.json
for s in 5 6 7 8 9; do many+=",$R/mesh_factor/hog_real_seed$s/hog_100_seeds.json"; done
for tag in own other; do
  add=$B12/hog_12_seeds_20x_synthetic_hog.json,$H/hog_12_seeds_20x_synthetic_hog.json
  [ $tag = other ] && add=$B12/hog_12_seeds_20x_synthetic_hog$O.json,$B/hog_12_seeds_20x_synthetic_hog$O.json
  PYTHONPATH=. python $R/gap_closed.py --few "$B12/hog_12_seeds.json,$H/hog_12_seeds.json" --added "$add" \
    --many "$many" --out $D/hog_12_10seeds_gap_$tag.md > /dev/null \
    --title "HOG, drones, seeds 0-9, 12 seeds + 20x synthetic ($tag backgrounds) against 12 and 100 real (stop 68)"
done
# the same 12-seed detectors on the validation videos (read back; seeds 0-4 bg12_val, 5-9 bg12_val_b)
V0=$R/hog_12_share/bg12_val; V1=$R/hog_12_share/bg12_val_b
three_way "$V0 $V1" hog_12_seeds.json hog_12_seeds_20x_synthetic_hog "12 real only" $D/hog_12_val10
# the CNN, blurs left out (its default), 100 seeds, built-in fits
if [ $# -ge 1 ]; then
  three_way "$1" cnn_100_seeds.json $C "real only" $D/cnn_100
  # stop 68: the same detectors on the validation videos (seeds 5-7 cnn_val_a, 8-9 cnn_val_b; read back)
  three_way "$D/cnn_val_a $D/cnn_val_b" cnn_100_seeds.json $C "real only" $D/cnn_100_val
fi
# stop 69: the CNN on 10 training seeds. Validation: seeds 0-1 cnn_val04_a, 2-4 cnn_val04_b (trained here, the own
# backgrounds of seeds 3-4 read back), 5-9 as above; test: seeds 0-4 cnn_test04 (read back), 5-9 cnn_a, cnn_b
three_way "$D/cnn_val04_a $D/cnn_val04_b" cnn_100_seeds.json $C "real only" $D/cnn_100_val04
three_way "$D/cnn_val04_a $D/cnn_val04_b $D/cnn_val_a $D/cnn_val_b" cnn_100_seeds.json $C "real only" $D/cnn_100_val10
if [ -d $D/cnn_test04 ]; then
  three_way "$D/cnn_test04 $D/cnn_a $D/cnn_b" cnn_100_seeds.json $C "real only" $D/cnn_100_10
fi
