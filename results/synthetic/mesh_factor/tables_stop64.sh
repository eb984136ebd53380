#!/usr/bin/env bash
# Stop 64's tables from its cells (every cell from this machine's fits; trains nothing). Repository root.
set -euo pipefail
D=results/synthetic/mesh_factor; T=results/learning_curve/video_diversity/table.py
S=hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog
rows() { for s in 0 1 2 3 4; do echo "$D/$1_seed$s/$2.json=$3"; done; }
mapfile -t BI < <(rows hog_builtin ${S}_builtin "+20x, built-in fits")
mapfile -t GL < <(rows hog_glb $S "+20x, quadcopter.glb fits")
mapfile -t BG < <(rows hog_builtin_gnoise ${S}_builtin_gnoise "+20x, built-in fits with the .glb fits' sigma_n")
mapfile -t GB < <(rows hog_glb_bnoise ${S}_glb_bnoise "+20x, .glb fits with the built-in fits' sigma_n")
mapfile -t RO < <(rows hog_real hog_100_seeds "real only")
PYTHONPATH=. python $T "${RO[@]}" "${BI[@]}" "${GL[@]}" --out $D/hog_5seeds_vs_real.md
PYTHONPATH=. python $T "${BI[@]}" "${GL[@]}" "${BG[@]}" --out $D/sigma_n_transplant_vs_builtin.md
PYTHONPATH=. python $T "${GL[@]}" "${GB[@]}" --out $D/sigma_n_transplant_vs_glb.md
