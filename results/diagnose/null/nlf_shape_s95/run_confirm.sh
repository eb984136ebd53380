#!/bin/bash
# Stop 95: the NLF-shape rule was made after seeing the fresh 11000 gamma 1.4 cases, so it is confirmed on cases
# never seen (seed base 13000): gamma and shot noise at both strengths. Then the three fresh-11000 colour rows that
# ran before this stop's floor change are rerun from their cached cases on the final code.
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/nlf_shape_s95/13000
mkdir -p $O
for E in gamma shot_noise; do
  for S in alt default; do
    sfx=$([ $S = alt ] && echo _alt || true)
    $B --cases 5 --base-seed 13000 --hidden $E --strength $S --workdir outputs/fresh13000_$E$sfx --out $O/power5_$E$sfx.json
  done
done
F=results/diagnose/null/fresh11000
for E in haze chromatic_aberration white_balance; do
  $B --cases 5 --base-seed 11000 --hidden $E --strength default --colour --workdir outputs/fresh11000_${E}_colour \
     --out $F/power5_${E}_colour.json
done
