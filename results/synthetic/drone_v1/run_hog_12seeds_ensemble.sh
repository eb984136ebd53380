#!/bin/bash
# Stop 29: issue 16's 12-seed HOG comparison (run_hog_12seeds.sh, test split, training seeds 0 1 2) again with the
# default box map since stop 28 (the mean of the ridge and CNN maps; stop 27 measured it with the ridge map).
# (a) 12 real seeds, then the d_HOG fits of each training seed's own 12-seed set (synthaug fit defaults, as
# run_hog_12seeds.sh), (b) 12 seeds + 20x synthetic (paired against (a)), (c) 100 real seeds.
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
D=results/synthetic/drone_v1
COMMON="--class drone --detectors hog --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split test --training-seeds 0 1 2"
echo "== (a) 12 real seeds only"; date -u
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 12 --out $D/hog_12seeds_real_ensemble
echo "== d_HOG fits of the 12-seed sets"; date -u
mkdir -p data/runs/fits
for s in 0 1 2; do
  [[ -f data/runs/fits/drone_12_seed${s}_hog.json ]] || /usr/bin/time -f "fit seed $s: %e s" python -m synthaug.cli fit \
    --seed-set data/runs/ingest_drone_seed$s/seedsets/drone_12 --mesh ../shared/data/meshes/quadcopter.glb --distance hog \
    --out data/runs/fits/drone_12_seed${s}_hog.json --workers 1 --no-progress
done
echo "== (b) 12 real seeds + 20x synthetic"; date -u
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 12 --synthetic-ratios 20 \
  --params 'data/runs/fits/drone_12_seed{seed}_hog.json' --fit-distance hog --out $D/hog_12seeds_ensemble
echo "== (c) 100 real seeds only"; date -u
/usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 100 --out $D/hog_12seeds_real100_ensemble
echo "== done"; date -u
