#!/usr/bin/env bash
# Stop 114: the rows where the frames' blur check can change a finding (every stored row that named defocus in any
# case), rerun with the check, plus the defocus row at the low end of its realistic range (sigma 0.7 frame px).
# usage: bash run.sh BASE ROW...   (ROW as run_rows.sh's, or sigma0.7 for the extra defocus row)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
base=$1; shift
out=results/diagnose/null/defocus_s114/$base
mkdir -p "$out"
pre=$([ "$base" = 8000 ] && echo bench_diagnose_power5 || echo "fresh$base")
for row in "$@"; do
  if [ "${row#sigma}" != "$row" ]; then
    s=${row#sigma}
    python results/diagnose/null/defocus_s114/bench_sigma.py "$s" --threads 1 --cases 5 --base-seed "$base" \
      --hidden defocus --workdir "outputs/${pre}_defocus_sigma$s" --out "$out/power5_defocus_sigma$s.json"
  else
    OUT=$out bash results/diagnose/null/periodic_s96/run_rows.sh "$base" "$row"
  fi
done
