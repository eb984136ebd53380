#!/bin/bash
# Stop 96: the whole judged power table on a third set of cases never seen by any rule or floor (seed base 13000),
# today's code and floors: the rows not already run this stop (run_confirm.sh: interlacing; run_replicate.sh:
# exposure at auto 0.5, lens at both strengths; run_rows.sh 13000: gamma at both; stop 95's run_confirm.sh made the
# shot-noise cases, rerun here). Two halves (a, b), one job each, side by side on the two cores.
set -e
cd "$(dirname "$0")/../../../.."
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/periodic_s96/13000
mkdir -p $O
case "$1" in
  a) GRAY="defocus rotor_blur rolling_shutter sharpening compression shot_noise"; COLOUR="haze chromatic_aberration"
     EXTRA="exposure:alt" ;;
  b) GRAY="vignetting column_pattern specular"; COLOUR="white_balance"; EXTRA="" ;;
  *) echo "usage: $0 a|b" >&2; exit 2 ;;
esac
for S in default alt; do
  sfx=$([ $S = alt ] && echo _alt || true)
  for E in $COLOUR; do
    $B --cases 5 --base-seed 13000 --hidden $E --strength $S --colour --workdir outputs/fresh13000_${E}_colour$sfx \
       --out $O/power5_${E}_colour$sfx.json
  done
  for E in $GRAY; do
    $B --cases 5 --base-seed 13000 --hidden $E --strength $S --workdir outputs/fresh13000_$E$sfx \
       --out $O/power5_$E$sfx.json
  done
done
for X in $EXTRA; do
  E=${X%:*}
  $B --cases 5 --base-seed 13000 --hidden $E --strength alt --workdir outputs/fresh13000_${E}_alt --out $O/power5_${E}_alt.json
done
