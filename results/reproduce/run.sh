#!/bin/bash
# Issue 15: `synthaug train` + `synthaug detect --frame-stride 5` + `synthaug evaluate` on a folder of videos the
# project never saw by name (the protocol's 16 drone test videos, renamed CLIP_01..16 into data/unseen/), to be
# compared with the protocol's AP of the same detector (HOG, 100 real seeds, training seed 0: 0.347; mean of 3
# seeds 0.348 [0.187, 0.583], results/learning_curve/drone_v6).
# `run.sh v2`: the same under protocol halmstad_v2 (frames without a labelled box not scored: `synthaug evaluate
# --unlabelled-frames skip`), into data/unseen_v2 and eval_v2 (compare: results/learning_curve/drone_v2/hog_100/
# hog_100_seeds.json, seed 0). Both train with the ridge box map, the map of the protocol cells they are compared with
# (the default became the ensemble after the v1 run).
set -e
if [ "${1:-v1}" = v2 ]; then
  U=data/unseen_v2; EVAL_EXTRA="--unlabelled-frames skip"; OUT=results/reproduce/eval_v2
else
  U=data/unseen; EVAL_EXTRA=""; OUT=results/reproduce/eval
fi
cd "$(dirname "$0")/../.."
export OMP_NUM_THREADS=1
S=../shared/data/halmstad
rm -rf $U && mkdir -p $U/videos $U/labels $U/dets
k=0
for stem in V_DRONE_056 V_DRONE_057 V_DRONE_058 V_DRONE_059 V_DRONE_076 V_DRONE_077 V_DRONE_078 V_DRONE_079 \
            V_DRONE_106 V_DRONE_107 V_DRONE_108 V_DRONE_109 V_DRONE_111 V_DRONE_112 V_DRONE_113 V_DRONE_114; do
  k=$((k + 1)); n=$(printf "CLIP_%02d" $k)
  ln -s "$(realpath $S/videos/$stem.mp4)" $U/videos/$n.mp4
  ln -s "$(realpath $S/labels/$stem.json)" $U/labels/$n.json
done
t0=$(date +%s)
# 1. train (the protocol's training videos: the split file keeps the test videos out)
synthaug train --detector hog --class drone --videos $S/videos --labels $S/labels --split configs/splits/halmstad.json \
  --seed-counts 100 --seed 0 --box-model ridge --out $U/hog.pt --no-progress
t1=$(date +%s)
# 2. detect on every video of the new folder, every 5th frame (the protocol's test stride)
for v in $U/videos/*.mp4; do
  synthaug detect --video $v --checkpoint $U/hog.pt --frame-stride 5 --out $U/dets/$(basename $v .mp4).json --no-progress
done
t2=$(date +%s)
# 3. evaluate against the folder's labels
synthaug evaluate --detections $U/dets/*.json --labels $U/labels $EVAL_EXTRA --out $OUT
t3=$(date +%s)
echo "wall: train $((t1 - t0)) s, detect $((t2 - t1)) s, evaluate $((t3 - t2)) s"
