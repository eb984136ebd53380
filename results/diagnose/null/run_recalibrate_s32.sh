#!/bin/bash
# Stop 32: the null calibration rerun after the frames' blockiness became the smaller of its column and row values
# (a codec's square blocks lift both directions; a sensor's fixed column pattern one: at sd 0.04 it was named
# compression (frame) in 1 of 5 power cases). The same four calibration and fresh sets as run_recalibrate_s30.sh,
# the same seeds and fits, regenerated on this machine; the two calibration sets side by side, then the floors, then
# the two fresh sets side by side (2 cores).
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
B="python benchmarks/bench_diagnose_null.py"
N=results/diagnose/null
T() { /usr/bin/time -f "wall %e s: $*" "$@"; }
echo "== calibration: 24 cases, the tests' fit | 20 cases, synthaug fit's"; date -u
T $B --cases 24 --rules hand --out $N/calibration_set_hand.json > /dev/null &
T $B --cases 20 --base-seed 4000 --fit full --budget 800 --step-deg 10 --sprite-size 64 \
  --workdir outputs/bench_diagnose_null_full --out $N/full_fit_calibrated.json > /dev/null &
wait
echo "== floors"; date -u
$B --floors-from $N/calibration_set_hand.json $N/full_fit_calibrated.json --write-floors synthaug/diagnose/null_floors.py
echo "== fresh: 24 cases, the tests' fit | 20 cases, synthaug fit's"; date -u
T $B --cases 24 --base-seed 3000 --workdir outputs/bench_diagnose_null_fresh --out $N/fresh_pooled.json > /dev/null &
T $B --cases 20 --base-seed 5000 --fit full --budget 800 --step-deg 10 --sprite-size 64 \
  --workdir outputs/bench_diagnose_null_full_fresh --out $N/fresh_full_fit_calibrated.json > /dev/null &
wait
echo "== done"; date -u
