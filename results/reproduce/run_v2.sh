#!/bin/bash
# Issue 15 under protocol halmstad_v2: run.sh's three user commands, the frames without a labelled box not scored
# (`synthaug evaluate --unlabelled-frames skip`), to be compared with the v2 protocol cell of the same detector
# (HOG, 100 real seeds, training seed 0, ridge box map: results/learning_curve/drone_v2/hog_100/hog_100_seeds.json).
set -e
cd "$(dirname "$0")/../.."
export OMP_NUM_THREADS=1
S=../shared/data/halmstad
rm -rf data/unseen_v2 && mkdir -p data/unseen_v2/videos data/unseen_v2/labels data/unseen_v2/dets
k=0
for stem in V_DRONE_056 V_DRONE_057 V_DRONE_058 V_DRONE_059 V_DRONE_076 V_DRONE_077 V_DRONE_078 V_DRONE_079 \
            V_DRONE_106 V_DRONE_107 V_DRONE_108 V_DRONE_109 V_DRONE_111 V_DRONE_112 V_DRONE_113 V_DRONE_114; do
  k=$((k + 1)); n=$(printf "CLIP_%02d" $k)
  ln -s "$(realpath $S/videos/$stem.mp4)" data/unseen_v2/videos/$n.mp4
  ln -s "$(realpath $S/labels/$stem.json)" data/unseen_v2/labels/$n.json
done
t0=$(date +%s)
synthaug train --detector hog --class drone --videos $S/videos --labels $S/labels --split configs/splits/halmstad.json \
  --seed-counts 100 --seed 0 --box-model ridge --out data/unseen_v2/hog.pt --no-progress
t1=$(date +%s)
for v in data/unseen_v2/videos/*.mp4; do
  synthaug detect --video $v --checkpoint data/unseen_v2/hog.pt --frame-stride 5 --out data/unseen_v2/dets/$(basename $v .mp4).json --no-progress
done
t2=$(date +%s)
synthaug evaluate --detections data/unseen_v2/dets/*.json --labels data/unseen_v2/labels --unlabelled-frames skip \
  --out results/reproduce/eval_v2
t3=$(date +%s)
echo "wall: train $((t1 - t0)) s, detect $((t2 - t1)) s, evaluate $((t3 - t2)) s"
