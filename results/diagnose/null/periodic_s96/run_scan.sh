#!/usr/bin/env bash
# Stop 96: the periodic_* measures (band from 0.25 cycles per frame px, floors remade) on every cached case of a
# power table and the clean sets; which cases' significance moved is read against the stored rows' counts.
# usage: bash results/diagnose/null/periodic_s96/run_scan.sh 8000|11000|clean
set -euo pipefail
cd "$(dirname "$0")/../../../.."
which=$1
groups=()
if [ "$which" = clean ]; then
  for w in bench_diagnose_null_hand2000 bench_diagnose_null_full fresh11000_clean fresh12000_clean_full \
           bench_diagnose_null_colour_paint bench_diagnose_null_colour_paint_fresh fresh11000_clean_colour; do
    groups+=("$w=outputs/$w"); done
else
  pre=$([ "$which" = 8000 ] && echo bench_diagnose_power5 || echo fresh11000)
  for d in outputs/${pre}_*; do
    case "$d" in *_haze|*_haze_alt|*_clean*) continue;; esac  # haze: judged on colour cases; clean: its own scan
    groups+=("$(basename "$d")=$d"); done
fi
PYTHONPATH=. python results/diagnose/null/periodic_s96/recalibrate.py --fresh "${groups[@]}" \
  --out "results/diagnose/null/periodic_s96/scan_$which.json"
