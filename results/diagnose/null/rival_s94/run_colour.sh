#!/bin/bash
# Stop 94: the colour rows, the clean colour cases and the fresh haze rows rerun with the stop's final code
# (explained_better, and haze / chromatic aberration on a painted object against the paint alone). Cached cases:
# the diagnosis only (the fresh haze cases were made by run_fresh.sh). Part "a" or "b" (two cores).
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/rival_s94
if [ "$1" = a ]; then
  $B --cases 20 --base-seed 3000 --colour --workdir outputs/bench_diagnose_null_colour_paint --out $O/colour_clean_paint.json
  for E in haze white_balance chromatic_aberration; do
    for S in default alt; do
      sfx=$([ $S = alt ] && echo _alt || true)
      $B --cases 5 --base-seed 8000 --hidden $E --strength $S --colour \
         --workdir outputs/bench_diagnose_power5_${E}_colour$sfx --out $O/power5_${E}_colour$sfx.json
    done
  done
else
  $B --cases 20 --base-seed 5000 --colour --workdir outputs/bench_diagnose_null_colour_paint_fresh \
     --out $O/colour_clean_paint_fresh.json
  for S in default alt; do
    sfx=$([ $S = alt ] && echo _alt || true)
    $B --cases 5 --base-seed 9000 --hidden haze --strength $S --colour --workdir outputs/fresh9000_haze_colour$sfx \
       --out $O/fresh9000/power5_haze_colour$sfx.json
  done
fi
