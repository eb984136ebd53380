#!/usr/bin/env bash
# Stop 114: rows diagnosed by the code before the frames' blur check (BASE_CODE: a checkout of f24a0a5, e.g.
# git worktree add /work/base f24a0a5), from the cases run.sh made, into before/BASE (the same machine as the rows
# after). usage: BASE_CODE=DIR bash run_before.sh BASE ROW...   (ROW as run.sh's)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
base=$1; shift
out=results/diagnose/null/defocus_s114/before/$base
mkdir -p "$out"
pre=$([ "$base" = 8000 ] && echo bench_diagnose_power5 || echo "fresh$base")
for row in "$@"; do
  if [ "${row#sigma}" != "$row" ]; then
    s=${row#sigma}
    PYTHONPATH="$BASE_CODE" python results/diagnose/null/defocus_s114/bench_sigma.py "$s" --threads 1 --cases 5 \
      --base-seed "$base" --hidden defocus --workdir "outputs/${pre}_defocus_sigma$s" \
      --out "$out/power5_defocus_sigma$s.json"
  else
    effect=${row%_alt}; strength=$([ "$row" != "$effect" ] && echo alt || echo default)
    colour=$(case "$effect" in *_colour) echo --colour;; esac)
    effect=${effect%_colour}
    # the old checkout's benchmark and package (the editable install points at this checkout)
    (cd "$BASE_CODE" && PYTHONPATH="$BASE_CODE" python benchmarks/bench_diagnose_null.py --threads 1 --cases 5 \
      --base-seed "$base" --hidden "$effect" --strength "$strength" $colour --workdir "$OLDPWD/outputs/${pre}_$row" \
      --out "$OLDPWD/$out/power5_$row.json")
  fi
done
