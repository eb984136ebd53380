#!/usr/bin/env bash
# Diagnosis time per 60-seed case before and after stop 113's frame-evidence speed-up, side by side on the same
# cached cases (a missing case is made by the first run, its data and converged fit untimed; only the diagnosis is
# timed, one thread).
# BASE: a checkout of the code before (git worktree add BASE <commit>); run from the repository root.
# Usage: BASE=/work/base bash results/diagnose/speed_s113/run.sh
set -euo pipefail
out=results/diagnose/speed_s113
rows=("gamma alt outputs/fresh13000_gamma_alt" "sharpening alt outputs/fresh13000_sharpening_alt"
      "lens_distortion alt outputs/s113_13000_lens_distortion_alt")
for rep in 1 2; do
  for row in "${rows[@]}"; do
    set -- $row
    for which in before after; do
      if [ "$which" = before ]; then pp="$BASE"; bench="$BASE/benchmarks/bench_diagnose_null.py"
      else pp="$PWD"; bench=benchmarks/bench_diagnose_null.py; fi
      PYTHONPATH="$pp" python "$bench" --threads 1 --cases 5 --base-seed 13000 --hidden "$1" --strength "$2" \
        --workdir "$3" --out "$out/${1}_${2}_${which}_${rep}.json" 2>&1 | grep "^case" | sed "s/^/$which $1 $rep /"
    done
  done
done
