#!/bin/bash
# Stop 96: the whole judged power table on a third set of cases never seen by any rule or floor (seed base 13000),
# today's code and floors: the rows not already run this stop (run_confirm.sh: interlacing; run_replicate.sh:
# exposure at auto 0.5, lens at both strengths; run_rows.sh 13000: gamma at both; stop 95's run_confirm.sh made the
# shot-noise cases, rerun here). Two halves (a, b), one job each, side by side on the two cores; each row through
# run_rows.sh 13000 (the colour candidates on colour cases: ROW_colour).
set -e
case "$1" in
  a) GRAY="defocus rotor_blur rolling_shutter sharpening compression shot_noise"; COLOUR="haze chromatic_aberration"
     EXTRA="exposure_alt" ;;
  b) GRAY="vignetting column_pattern specular"; COLOUR="white_balance"; EXTRA="" ;;
  *) echo "usage: $0 a|b" >&2; exit 2 ;;
esac
rows=()
for sfx in "" _alt; do
  for E in $COLOUR; do rows+=("${E}_colour$sfx"); done
  for E in $GRAY; do rows+=("$E$sfx"); done
done
exec bash "$(dirname "$0")/run_rows.sh" 13000 "${rows[@]}" $EXTRA
