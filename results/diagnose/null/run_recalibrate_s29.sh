#!/bin/bash
# Stop 29: the null calibration rerun after two residual measures were added (column_pattern, row_pattern:
# gains fixed in the frame's columns / rows). The same four calibration and fresh sets as results/diagnose/README.md
# ("Commands"), the same seeds and fits, regenerated on this machine (nothing was cached); the floors written
# from the two calibration sets, then the fresh false-alarm checks under them.
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
B="python benchmarks/bench_diagnose_null.py"
N=results/diagnose/null
T() { /usr/bin/time -f "wall %e s" "$@"; }
echo "== calibration: 24 cases, the tests' fit"; date -u
T $B --cases 24 --rules hand --out $N/calibration_set_hand.json
echo "== calibration: 20 cases, synthaug fit's"; date -u
T $B --cases 20 --base-seed 4000 --fit full --budget 800 --step-deg 10 --sprite-size 64 \
  --workdir outputs/bench_diagnose_null_full --out $N/full_fit_calibrated.json
echo "== floors"; date -u
$B --floors-from $N/calibration_set_hand.json $N/full_fit_calibrated.json --write-floors synthaug/diagnose/null_floors.py
echo "== fresh: 24 cases, the tests' fit"; date -u
T $B --cases 24 --base-seed 3000 --workdir outputs/bench_diagnose_null_fresh --out $N/fresh_pooled.json
echo "== fresh: 20 cases, synthaug fit's"; date -u
T $B --cases 20 --base-seed 5000 --fit full --budget 800 --step-deg 10 --sprite-size 64 \
  --workdir outputs/bench_diagnose_null_full_fresh --out $N/fresh_full_fit_calibrated.json
echo "== done"; date -u
