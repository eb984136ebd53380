#!/bin/bash
# Stop 95: the gamma and shot-noise rows rerun from their cached cases with the NLF's shape deciding a rising NLF's
# cause where it is conclusive (screening.shape_verdict): the power table's cases (8000) and the fresh ones (11000).
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/nlf_shape_s95
for base in 8000 11000; do
  mkdir -p $O/$base
  for E in gamma shot_noise; do
    for S in default alt; do
      sfx=$([ $S = alt ] && echo _alt || true)
      W=$([ $base = 8000 ] && echo outputs/bench_diagnose_power5_$E$sfx || echo outputs/fresh11000_$E$sfx)
      $B --cases 5 --base-seed $base --hidden $E --strength $S --workdir $W --out $O/$base/power5_$E$sfx.json
    done
  done
done
