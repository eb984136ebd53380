#!/usr/bin/env bash
# Stop 114: the defocus rows at sigma 0.7 diagnosed by the code before the frames' blur check (BASE_CODE: a checkout of
# f24a0a5, e.g. git worktree add /work/base f24a0a5), from the cases run.sh made. usage: BASE_CODE=DIR bash run_before.sh BASE...
set -euo pipefail
cd "$(dirname "$0")/../../../.."
for base in "$@"; do
  pre=$([ "$base" = 8000 ] && echo bench_diagnose_power5 || echo "fresh$base")
  mkdir -p "results/diagnose/null/defocus_s114/before/$base"
  PYTHONPATH="$BASE_CODE" python results/diagnose/null/defocus_s114/bench_sigma.py 0.7 --threads 1 --cases 5 \
    --base-seed "$base" --hidden defocus --workdir "outputs/${pre}_defocus_sigma0.7" \
    --out "results/diagnose/null/defocus_s114/before/$base/power5_defocus_sigma0.7.json"
done
