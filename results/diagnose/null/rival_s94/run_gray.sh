#!/bin/bash
# Stop 94: the gray rows where a rival out-explained the named-first effect in the stored first rounds (new cases:
# data, fit and diagnosis).
set -e
B="python benchmarks/bench_diagnose_null.py --threads 1"
O=results/diagnose/null/rival_s94
$B --cases 5 --base-seed 8000 --hidden haze --workdir outputs/bench_diagnose_power5_haze --out $O/power5_haze.json
$B --cases 5 --base-seed 8000 --hidden lens_distortion --workdir outputs/bench_diagnose_power5_lens_distortion \
   --out $O/power5_lens_distortion.json
$B --cases 5 --base-seed 8000 --hidden lens_distortion --strength alt \
   --workdir outputs/bench_diagnose_power5_lens_distortion_alt --out $O/power5_lens_distortion_alt.json
