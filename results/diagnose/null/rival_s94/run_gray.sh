#!/bin/bash
# Stop 94: every judged gray power row rerun with explained_better (the final code of the stop): the cases are made
# anew where outputs/ does not hold them (data, converged fit), then diagnosed. Haze on gray is run too (not judged:
# haze is judged on colour data).
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/rival_s94
for E in haze lens_distortion defocus gamma rotor_blur rolling_shutter sharpening exposure compression vignetting \
         shot_noise interlacing column_pattern specular; do
  for S in default alt; do
    sfx=$([ $S = alt ] && echo _alt || true)
    $B --cases 5 --base-seed 8000 --hidden $E --strength $S --workdir outputs/bench_diagnose_power5_$E$sfx \
       --out $O/power5_$E$sfx.json
  done
done
