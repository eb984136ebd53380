#!/bin/bash
# Stop 94: the colour rows and the clean colour cases rerun with explained_better (cached cases: the diagnosis only).
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/rival_s94
$B --cases 20 --base-seed 3000 --colour --workdir outputs/bench_diagnose_null_colour_paint --out $O/colour_clean_paint.json
$B --cases 20 --base-seed 5000 --colour --workdir outputs/bench_diagnose_null_colour_paint_fresh --out $O/colour_clean_paint_fresh.json
for E in haze white_balance chromatic_aberration; do
  for S in default alt; do
    sfx=$([ $S = alt ] && echo _alt || true)
    $B --cases 5 --base-seed 8000 --hidden $E --strength $S --colour --workdir outputs/bench_diagnose_power5_${E}_colour$sfx \
       --out $O/power5_${E}_colour$sfx.json
  done
done
