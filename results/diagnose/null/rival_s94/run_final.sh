#!/bin/bash
# Stop 94, last: every power row and the clean colour cases on the stop's final code (the forward-selection re-screen
# added after run_gray.sh / run_colour.sh), cases cached in outputs/ by those runs: the diagnosis only. Part a or b.
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
N=results/diagnose/null
if [ "$1" = a ]; then
  EFFECTS="haze lens_distortion defocus gamma rotor_blur rolling_shutter sharpening"
  $B --cases 20 --base-seed 3000 --colour --workdir outputs/bench_diagnose_null_colour_paint \
     --out $N/rival_s94/colour_clean_paint.json
else
  EFFECTS="exposure compression vignetting shot_noise interlacing column_pattern specular"
  $B --cases 20 --base-seed 5000 --colour --workdir outputs/bench_diagnose_null_colour_paint_fresh \
     --out $N/rival_s94/colour_clean_paint_fresh.json
fi
for E in $EFFECTS; do
  for S in default alt; do
    sfx=$([ $S = alt ] && echo _alt || true)
    $B --cases 5 --base-seed 8000 --hidden $E --strength $S --workdir outputs/bench_diagnose_power5_$E$sfx \
       --out $N/power5_$E$sfx.json
  done
done
if [ "$1" = a ]; then
  for E in haze white_balance chromatic_aberration; do
    for S in default alt; do
      sfx=$([ $S = alt ] && echo _alt || true)
      $B --cases 5 --base-seed 8000 --hidden $E --strength $S --colour \
         --workdir outputs/bench_diagnose_power5_${E}_colour$sfx --out $N/power5_${E}_colour$sfx.json
    done
  done
fi
