#!/usr/bin/env bash
# Stop 66: HOG + 20x from fits of quadcopter.glb decimated to the built-in quadcopter's 888 faces (run_decimated.sh;
# and, where every seed given has it, the decimated mesh with its footprint made square, tag glbsq), paired against
# the quadcopter.glb fits and the built-in fits of the same seeds (stored cells); the CNN's decimated cells (seeds
# 0-4, cnn_glbdec/) against its .glb and built-in cells. Trains nothing.
# usage (repository root): results/synthetic/mesh_factor/tables_decimated.sh "0 1 2 3 4 5 6 7 8 9" ["0 1 2 3 4"]
#   (the second list: the seeds with a glbsq cell)
set -euo pipefail
R=results/synthetic; D=$R/mesh_factor; T=results/learning_curve/video_diversity/table.py
G=hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog
# one table.py argument per seed of $2: the HOG + 20x cell of mesh tag $1 ("" for quadcopter.glb), labelled $3
cells() { for s in $2; do echo "$D/hog_${1:-glb}_seed$s/$G${1:+_$1}.json=$3"; done; }
mapfile -t GL < <(cells "" "$1" "+20x, quadcopter.glb fits")
mapfile -t DE < <(cells glbdec "$1" "+20x, quadcopter.glb decimated to 888 faces")
mapfile -t BI < <(cells builtin "$1" "+20x, built-in fits")
RO=(); for s in $1; do RO+=("$D/hog_real_seed$s/hog_100_seeds.json=real only"); done
PYTHONPATH=. python $T "${GL[@]}" "${DE[@]}" "${BI[@]}" "${RO[@]}" --out $D/hog_decimated_vs_glb.md
PYTHONPATH=. python $T "${BI[@]}" "${DE[@]}" --out $D/hog_decimated_vs_builtin.md
# the decimated mesh with a square footprint, on the seeds that have it, against the decimated and built-in cells
if [ -n "${2:-}" ]; then
  mapfile -t SQ < <(cells glbsq "$2" "+20x, decimated, footprint square")
  mapfile -t DE2 < <(cells glbdec "$2" "+20x, quadcopter.glb decimated to 888 faces")
  mapfile -t BI2 < <(cells builtin "$2" "+20x, built-in fits")
  PYTHONPATH=. python $T "${DE2[@]}" "${SQ[@]}" "${BI2[@]}" --out $D/hog_square_vs_decimated.md
fi
# the CNN (blurs left out, its default), seeds 0-4
NB=without_boundary_blur_and_motion_blur; C=cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog
if [ -f "$D/cnn_glbdec/${C}_glbdec_$NB.json" ]; then
  CG=(); for f in $R/placement/cnn_100 $D/cnn_glb_seed3 $D/cnn_glb_seed4; do
    CG+=("$f/${C}_$NB.json=+20x, quadcopter.glb fits"); done
  CB=(); for f in $D/cnn_100_builtin $D/cnn_builtin_seed3 $D/cnn_builtin_seed4; do
    CB+=("$f/${C}_builtin_$NB.json=+20x, built-in fits"); done
  PYTHONPATH=. python $T "${CG[@]}" "$D/cnn_glbdec/${C}_glbdec_$NB.json=+20x, quadcopter.glb decimated to 888 faces" \
    "${CB[@]}" "$R/cnn_figs/no_blurs/cnn_100_seeds.json=real only" --out $D/cnn_decimated_vs_glb.md
fi
