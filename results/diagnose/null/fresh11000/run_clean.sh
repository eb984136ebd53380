#!/bin/bash
# Stop 95: clean cases never seen by any rule or floor, on the final code of the stop (the signed absorbed floors):
# a) 20 gray cases, converged fit (seed base 11000), then 20 colour cases with painted objects (seed base 11000);
# b) 20 gray cases through the user's path, `synthaug fit` from a random start (seed base 12000; ≈ 1 min a case).
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/fresh11000
case "$1" in
  a) $B --cases 20 --base-seed 11000 --workdir outputs/fresh11000_clean --out $O/clean_gray.json
     $B --cases 20 --base-seed 11000 --colour --workdir outputs/fresh11000_clean_colour --out $O/clean_colour_paint.json ;;
  b) $B --cases 20 --base-seed 12000 --fit full --budget 800 --step-deg 10 --sprite-size 64 \
        --workdir outputs/fresh12000_clean_full --out $O/clean_gray_full_fit.json ;;
  *) echo "usage: $0 a|b" >&2; exit 2 ;;
esac
