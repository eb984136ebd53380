#!/usr/bin/env bash
# Stop 66: HOG + 20x from fits of quadcopter.glb decimated to the built-in's 888 faces (run_decimated.sh), paired
# against the quadcopter.glb fits and the built-in fits of the same seeds (stored cells; trains nothing).
# usage (repository root): results/synthetic/mesh_factor/tables_decimated.sh "0 1 2 3 4"
set -euo pipefail
D=results/synthetic/mesh_factor; T=results/learning_curve/video_diversity/table.py
G=hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog
GL=(); DE=(); BI=(); RO=()
for s in $1; do
  GL+=("$D/hog_glb_seed$s/$G.json=+20x, quadcopter.glb fits")
  DE+=("$D/hog_glbdec_seed$s/${G}_glbdec.json=+20x, quadcopter.glb decimated to 888 faces")
  BI+=("$D/hog_builtin_seed$s/${G}_builtin.json=+20x, built-in fits")
  RO+=("$D/hog_real_seed$s/hog_100_seeds.json=real only")
done
PYTHONPATH=. python $T "${GL[@]}" "${DE[@]}" "${BI[@]}" "${RO[@]}" --out $D/hog_decimated_vs_glb.md
PYTHONPATH=. python $T "${BI[@]}" "${DE[@]}" --out $D/hog_decimated_vs_builtin.md
