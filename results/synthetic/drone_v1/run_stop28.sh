#!/bin/bash
# Stop 28: a steadier mining stop. The CNN's 12-seed comparison (run_cnn_12seeds.sh + run_cnn_12seeds_extra.sh, test
# split, training seeds 0 1 2) again under the new rule: the mining round chosen by the highest validation AP of the
# same detections, one round of patience (--mining-select ap --mining-patience 1; chosen before any test number).
# Today's rule (fp, patience 0) is the cached cells of those scripts (their keys are unchanged).
#   KIND=cnn (default) STEP=ab|c|all: (a) 12 real seeds + (b) 12 seeds + 20x synthetic (d_CNN fits), (c) 100 real seeds
#   KIND=hog STEP=ab: the same (a) and (b) for HOG (d_HOG fits of run_hog_12seeds.sh)
#   RULE="--mining-select fp --mining-patience 0" TAG=_old: today's rule from the cache (trains nothing when cached)
#   EVAL=val STEP=a|c SEEDS=...: the protocol's validation frames instead (STEP=a: (a) alone), into *_val folders
set -e
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
D=results/synthetic/drone_v1
K=${KIND:-cnn}
RULE=${RULE:---mining-select ap --mining-patience 1}
TAG=${TAG:-_stop28}$([[ ${EVAL:-test} == val ]] && echo _val)
COMMON="--class drone --detectors $K --mesh ../shared/data/meshes/quadcopter.glb --no-scale-check --no-patches --eval-split ${EVAL:-test} --training-seeds ${SEEDS:-0 1 2} $RULE"
STEP=${STEP:-all}
if [[ $STEP == all || $STEP == ab ]]; then
  echo "== $K (a) 12 real seeds + (b) 12 seeds + 20x synthetic, rule: $RULE"; date -u
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 12 --synthetic-ratios 20 \
    --params "data/runs/fits/drone_12_seed{seed}_$K.json" --fit-distance $K --out $D/${K}_12seeds$TAG
fi
if [[ $STEP == a ]]; then
  echo "== $K (a) 12 real seeds, rule: $RULE"; date -u
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 12 --out $D/${K}_12seeds_a$TAG
fi
if [[ $STEP == all || $STEP == c ]]; then
  echo "== $K (c) 100 real seeds, rule: $RULE"; date -u
  /usr/bin/time -f "wall %e s" python -m synthaug.evaluate.runner synthetic $COMMON --seed-counts 100 --out $D/${K}_12seeds_real100$TAG
fi
echo "== done"; date -u
