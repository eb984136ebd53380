#!/usr/bin/env bash
# Stop 64: HOG real only vs + 20x from this machine's built-in fits on every training seed given (trains nothing);
# stop 65: and the built-in fits against the quadcopter.glb ones, when every seed given has both.
# usage (repository root): results/synthetic/mesh_factor/tables_more_seeds.sh "0 1 2 3 4 5 6 7 8 9"
set -euo pipefail
D=results/synthetic/mesh_factor; T=results/learning_curve/video_diversity/table.py
S=hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin
RO=(); BI=()
for s in $1; do RO+=("$D/hog_real_seed$s/hog_100_seeds.json=real only"); BI+=("$D/hog_builtin_seed$s/$S.json=+20x, built-in fits"); done
PYTHONPATH=. python $T "${RO[@]}" "${BI[@]}" --out $D/hog_more_seeds_vs_real.md
# stop 65: the mesh on the same seeds, when every seed given has its quadcopter.glb cell
G=hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog
GL=(); for s in $1; do GL+=("$D/hog_glb_seed$s/$G.json=+20x, quadcopter.glb fits"); done
if ls "${GL[@]%=*}" > /dev/null 2>&1; then
  PYTHONPATH=. python $T "${BI[@]}" "${GL[@]}" "${RO[@]}" --out $D/hog_more_seeds_builtin_vs_glb.md
fi
