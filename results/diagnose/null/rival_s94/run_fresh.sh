#!/bin/bash
# Stop 94: fresh cases (seed base 9000, never seen while the rule was made) for the rows the rule was made on:
# haze on colour (its 0.85 case 2 was named defocus), lens +0.1 (its case 4 kept by the frames' corroboration),
# and defocus (the rival that lost its name there).
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/rival_s94/fresh9000
mkdir -p $O
for S in default alt; do
  sfx=$([ $S = alt ] && echo _alt || true)
  $B --cases 5 --base-seed 9000 --hidden haze --strength $S --colour --workdir outputs/fresh9000_haze_colour$sfx \
     --out $O/power5_haze_colour$sfx.json
  $B --cases 5 --base-seed 9000 --hidden lens_distortion --strength $S --workdir outputs/fresh9000_lens_distortion$sfx \
     --out $O/power5_lens_distortion$sfx.json
  $B --cases 5 --base-seed 9000 --hidden defocus --strength $S --workdir outputs/fresh9000_defocus$sfx \
     --out $O/power5_defocus$sfx.json
done
