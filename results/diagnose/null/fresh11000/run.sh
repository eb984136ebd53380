#!/bin/bash
# Stop 95: the whole judged power table again on cases never seen by any rule or floor (seed base 11000; the power
# table's cases are 8000-8004, the stop 94 confirmation 9000-9004). Every judged row at both strengths: the gray
# candidates on gray cases, chromatic aberration / white balance / haze on colour cases. Two halves (a, b), one job
# each, run side by side on the two cores.
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/fresh11000
case "$1" in
  a) GRAY="defocus gamma rotor_blur rolling_shutter sharpening exposure compression"; COLOUR="haze chromatic_aberration" ;;
  b) GRAY="vignetting shot_noise interlacing column_pattern specular lens_distortion"; COLOUR="white_balance" ;;
  *) echo "usage: $0 a|b" >&2; exit 2 ;;
esac
for S in default alt; do
  sfx=$([ $S = alt ] && echo _alt || true)
  for E in $COLOUR; do
    $B --cases 5 --base-seed 11000 --hidden $E --strength $S --colour --workdir outputs/fresh11000_${E}_colour$sfx \
       --out $O/power5_${E}_colour$sfx.json
  done
  for E in $GRAY; do
    $B --cases 5 --base-seed 11000 --hidden $E --strength $S --workdir outputs/fresh11000_$E$sfx \
       --out $O/power5_$E$sfx.json
  done
done
