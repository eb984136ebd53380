#!/bin/bash
# stop 103: AdaBoost at 100 drone seeds, calibrated test cells: real only, + 20x perturbed, + 20x copy-paste and the
# shape cell + 5x soft distractors, paired by training seed (seeds 0-2 stored before this stop, seeds 3-4 this stop).
# usage (repository root): results/synthetic/adaboost_distractors/frame_s103/tables.sh
set -e
D=results/synthetic/adaboost_distractors
I=$D/intel_cal_test F1=$D/frame_s101 F2=$D/frame_s102/soft5 P=$D/frame_s102/perturbed B=$D/frame_s103/baselines
N=$D/frame_s103/new_seeds
real=adaboost_100_seeds.json s5=$(ls $F2/seed0) cp=$(ls $B/seed0) pt=$(ls $P/seed0)
R=("$I/seed0/$real=real only" "$I/seed1/$real=real only" "$F1/seed2/$real=real only")
S=("$F2/seed0/$s5=shape + 5x soft distractors" "$F2/seed1/$s5=shape + 5x soft distractors"
   "$F2/seed2/$s5=shape + 5x soft distractors")
C=("$B/seed0/$cp=+ 20x copy-paste" "$B/seed1/$cp=+ 20x copy-paste" "$B/seed2/$cp=+ 20x copy-paste")
PT=("$P/seed0/$pt=+ 20x perturbed" "$P/seed1/$pt=+ 20x perturbed" "$B/seed2/$pt=+ 20x perturbed")
for s in 3 4 5 6; do   # the new seeds' real-only and soft cells, where made
  [ -f "$N/seed$s/$s5" ] || continue
  R+=("$N/seed$s/$real=real only"); S+=("$N/seed$s/$s5=shape + 5x soft distractors")
done
T="python results/learning_curve/video_diversity/table.py"
export PYTHONPATH=.
$T "${R[@]:0:3}" "${PT[@]}" "${C[@]}" "${S[@]:0:3}" --out $D/frame_s103/baselines_vs_real.md
$T "${C[@]}" "${S[@]:0:3}" --out $D/frame_s103/soft5_vs_copy_paste.md
$T "${PT[@]}" "${S[@]:0:3}" --out $D/frame_s103/soft5_vs_perturbed.md
$T "${R[@]}" "${S[@]}" --out $D/frame_s103/soft5_vs_real_all_seeds.md
