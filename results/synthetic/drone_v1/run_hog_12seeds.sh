#!/bin/bash
# issue 16's 12-seed target under protocol halmstad_v1, HOG, test split, training seeds 0 1 2:
#   (a) 12 real seeds only, (b) 12 real seeds + 20x synthetic (d_HOG fit of each training seed's own 12-seed set;
#   ratio 20 = the 100-seed experiments' ratio, pre-registered), (c) 100 real seeds only (recomputed, same code).
#   Optional (R50=1): (d) 12 seeds + 50x synthetic.
# Order: (a) first (its cells ingest each training seed's 12-seed set into data/runs/ingest_drone_seed{s}),
# then the d_HOG fits of those seed sets (synthaug fit defaults, as run_fits.sh), then (b) (the real-only
# cells of (a) come from the cache), then (c). Fresh data/runs: every cell is computed here.
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
D=results/synthetic/drone_v1
COMMON="--class drone --detectors hog --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split test --training-seeds 0 1 2"
STEP=${STEP:-all}
if [[ $STEP == all || $STEP == a ]]; then
  echo "== (a) 12 real seeds only"; date -u
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 12 --out $D/hog_12seeds_real
fi
if [[ $STEP == all || $STEP == fits ]]; then
  echo "== d_HOG fits of the 12-seed sets"; date -u
  mkdir -p data/runs/fits
  for s in 0 1 2; do
    /usr/bin/time -f "fit seed $s: %e s" python -m synthaug.cli fit --seed-set data/runs/ingest_drone_seed$s/seedsets/drone_12 \
      --mesh ../shared/data/meshes/quadcopter.glb --distance hog --out data/runs/fits/drone_12_seed${s}_hog.json --workers 1 --no-progress
  done
fi
if [[ $STEP == all || $STEP == b ]]; then
  echo "== (b) 12 real seeds + 20x synthetic (paired against (a), cached)"; date -u
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 12 --synthetic-ratios 20 \
    --params 'data/runs/fits/drone_12_seed{seed}_hog.json' --fit-distance hog --out $D/hog_12seeds
fi
if [[ $STEP == all || $STEP == c ]]; then
  echo "== (c) 100 real seeds only (recomputed)"; date -u
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 100 --out $D/hog_12seeds_real100
fi
if [[ $STEP == d ]]; then
  echo "== (d) 12 real seeds + 50x synthetic (optional)"; date -u
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 12 --synthetic-ratios 50 \
    --params 'data/runs/fits/drone_12_seed{seed}_hog.json' --fit-distance hog --out $D/hog_12seeds_r50
fi
echo "== done"; date -u
