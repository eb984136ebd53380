#!/usr/bin/env bash
# Stop 96: power rows rerun from their cached cases with today's code and floors, for the rows the periodic band
# can change. usage: bash run_rows.sh BASE ROW... (BASE 8000: outputs/bench_diagnose_power5_*, 11000:
# outputs/fresh11000_*; ROW as effect or effect_alt, e.g. interlacing interlacing_alt; clean: the 20 clean gray
# cases, clean_gray.json). OUT=DIR writes the rows there instead (stop 99: OUT=results/diagnose/null/clip_s99/13000)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
base=$1; shift
out=${OUT:-results/diagnose/null/periodic_s96/$base}
mkdir -p "$out"
pre=$([ "$base" = 8000 ] && echo bench_diagnose_power5 || echo "fresh$base")
for row in "$@"; do
  if [ "$row" = clean ]; then
    python benchmarks/bench_diagnose_null.py --threads 1 --cases 20 --base-seed "$base" \
      --workdir "outputs/${pre}_clean" --out "$out/clean_gray.json"
    continue
  fi
  effect=${row%_alt}; strength=$([ "$row" != "$effect" ] && echo alt || echo default)
  colour=$(case "$effect" in *_colour) echo --colour;; esac)
  effect=${effect%_colour}
  python benchmarks/bench_diagnose_null.py --threads 1 --cases 5 --base-seed "$base" --hidden "$effect" \
    --strength "$strength" $colour --workdir "outputs/${pre}_$row" --out "$out/power5_$row.json"
done
