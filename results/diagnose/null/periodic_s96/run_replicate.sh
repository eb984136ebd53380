#!/usr/bin/env bash
# Stop 96: the rows that failed out of sample at stop 95 (fresh 11000: exposure at auto 0.5, lens k1 +0.1; lens
# k1 -0.15 beside them), replicated on cases never seen (seed base 13000), today's code and floors.
set -euo pipefail
cd "$(dirname "$0")/../../../.."
out=results/diagnose/null/periodic_s96/13000
mkdir -p "$out"
for row in "exposure default" "lens_distortion alt" "lens_distortion default"; do
  set -- $row
  sfx=$([ "$2" = alt ] && echo _alt || true)
  python benchmarks/bench_diagnose_null.py --threads 1 --cases 5 --base-seed 13000 --hidden "$1" --strength "$2" \
    --workdir "outputs/fresh13000_$1$sfx" --out "$out/power5_$1$sfx.json"
done
