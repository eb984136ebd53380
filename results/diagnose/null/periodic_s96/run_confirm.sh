#!/usr/bin/env bash
# Stop 96: the periodic band's change judged on cases never seen (seed base 13000): interlacing at both strengths
# and 20 clean gray cases (converged fit), today's code and floors. Cases are cached in outputs/fresh13000_*.
set -euo pipefail
cd "$(dirname "$0")/../../../.."
out=results/diagnose/null/periodic_s96/13000
mkdir -p "$out"
python benchmarks/bench_diagnose_null.py --threads 1 --cases 5 --base-seed 13000 --hidden interlacing \
  --workdir outputs/fresh13000_interlacing --out "$out/power5_interlacing.json"
python benchmarks/bench_diagnose_null.py --threads 1 --cases 5 --base-seed 13000 --hidden interlacing --strength alt \
  --workdir outputs/fresh13000_interlacing_alt --out "$out/power5_interlacing_alt.json"
python benchmarks/bench_diagnose_null.py --threads 1 --cases 20 --base-seed 13000 \
  --workdir outputs/fresh13000_clean --out "$out/clean_gray.json"
