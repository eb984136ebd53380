#!/bin/bash
# Stop 87 (seeds 2-3 added at stop 88, the pose cell at stop 89): the tables of AdaBoost with the weak-learner critic
# (run.sh's cells), against real only and against stop 86's HOG critic on the same training seeds
# (../adaboost_critic/). Trains nothing (~1 min).
# usage (repository root): results/synthetic/adaboost_wl_critic/tables.sh
O=results/synthetic/adaboost_wl_critic
H=results/synthetic/adaboost_critic
T=results/learning_curve/video_diversity/table.py
export PYTHONPATH=${PYTHONPATH:-.}
real=adaboost_100_seeds.json
wl=adaboost_100_seeds_20x_synthetic_hog_quadcopter_share_0.25_the_25_least_synthetic_of_4x_drawn_of_each_seed_to_a_weak_learner_critic.json
hogc=adaboost_100_seeds_20x_synthetic_hog_quadcopter_share_0.25_the_25_least_synthetic_of_4x_drawn_of_each_seed.json
q8=adaboost_100_seeds_20x_synthetic_hog_quadcopter_share_0.25_8_bit_the_25_least_synthetic_of_4x_drawn_of_each_seed_to_a_weak_learner_critic.json
p8=adaboost_100_seeds_20x_synthetic_hog_quadcopter_fitted_poses_at_the_seeds_offsets_share_0.25_8_bit_the_25_least_synthetic_of_4x_drawn_of_each_seed_to_a_weak_learner_critic.json
Q8="+ 20x synthetic, 8-bit, weak-learner critic keeps 1/4"
P8="+ 20x synthetic, 8-bit, weak-learner critic, fitted rotations at the seeds' offsets"
# real_only DIR...: the real-only row from the first of a seed's folders that holds its real-only cell (fails if none)
real_only() { local r; for r in "$@"; do [ -f $r/$real ] && echo "$r/$real=real only" && return; done; return 1; }
for sp in val test; do
  rows=(); w=(); h=(); q=()
  for d in $O/${sp}_w[0-9]*; do
    [ -f $d/$real ] && rows+=("$d/$real=real only")
    [ -f $d/$wl ] && w+=("$d/$wl=+ 20x synthetic, weak-learner critic keeps 1/4")
    s=${d##*_w}; [ -f $H/${sp}_c$s/$hogc ] && h+=("$H/${sp}_c$s/$hogc=+ 20x synthetic, HOG critic keeps 1/4")
  done
  for d in $O/${sp}_q[0-9]*; do  # the seeds with a float cell too (the 8-bit cell alone: ${sp}_8bit_vs_real.md)
    [ -f $d/$q8 ] && [ -d $O/${sp}_w${d##*_q} ] && q+=("$d/$q8=$Q8")
  done
  python $T "${rows[@]}" "${w[@]}" "${q[@]}" "${h[@]}" --out $O/${sp}_vs_real.md
  [ ${#q[@]} -gt 0 ] && python $T "${w[@]}" "${q[@]}" --out $O/${sp}_8bit_vs_float.md
  # stop 88: the 8-bit cell on every seed it has (seed 3 has no float cell), against real only of the same seeds
  qr=(); qa=()
  for d in $O/${sp}_q[0-9]*; do
    s=${d##*_q}; r=$(real_only $d $O/${sp}_w$s) && qr+=("$r")
    [ -f $d/$q8 ] && qa+=("$d/$q8=$Q8")
  done
  [ ${#qa[@]} -gt 0 ] && python $T "${qr[@]}" "${qa[@]}" --out $O/${sp}_8bit_vs_real.md
  [ ${#h[@]} -gt 0 ] && python $T "${h[@]}" "${w[@]}" --out $O/${sp}_wl_vs_hog_critic.md
done
# stop 89: 8-bit + weak-learner critic with rotations around each seed's fitted one at its fitted offset (run.sh pN N
# --quantize on --pose-sampling fitted_at_seed) against real only on every seed it has (seed 4 has no 8-bit cell:
# *_all_seeds.md), and against real only and the 8-bit cell on the seeds that have both
for sp in val test; do
  ar=(); ap=(); pr=(); pq=(); pp=()
  for d in $O/${sp}_p[0-9]*; do
    s=${d##*_p}; [ -f $d/$p8 ] || continue
    r=$(real_only $d $O/${sp}_q$s $O/${sp}_w$s) || continue  # no pair without the seed's real only
    ar+=("$r"); ap+=("$d/$p8=$P8")
    [ -f $O/${sp}_q$s/$q8 ] || continue
    pr+=("$r"); pq+=("$O/${sp}_q$s/$q8=$Q8"); pp+=("$d/$p8=$P8")
  done
  [ ${#ap[@]} -gt 0 ] && python $T "${ar[@]}" "${ap[@]}" --out $O/${sp}_pose_vs_real_all_seeds.md
  [ ${#pp[@]} -gt 0 ] && python $T "${pr[@]}" "${pq[@]}" "${pp[@]}" --out $O/${sp}_pose_vs_real.md
  [ ${#pp[@]} -gt 0 ] && python $T "${pq[@]}" "${pp[@]}" --out $O/${sp}_pose_vs_8bit.md
done
# stop 90: the pose cell with shapes varied 0.3 around the mesh (run.sh sN N --quantize on --pose-sampling
# fitted_at_seed --shape-variation 0.3; trained on another machine than the cells above, ../adaboost_where/README.md)
# against real only and the pose cell of the same seeds
s8=adaboost_100_seeds_20x_synthetic_hog_quadcopter_fitted_poses_at_the_seeds_offsets_share_0.25_shapes_varied_0.3_8_bit_the_25_least_synthetic_of_4x_drawn_of_each_seed_to_a_weak_learner_critic.json
for sp in val test; do
  sr=(); sp8=(); ss=(); he=(); hs=(); ht=()
  for d in $O/${sp}_s[0-2]; do  # stop 90's three seeds (seed 3: the stop-91 block)
    s=${d##*_s}; [ -f $d/$s8 ] || continue
    r=$(real_only $O/${sp}_p$s $O/${sp}_q$s $O/${sp}_w$s) || continue
    if [ -f $O/${sp}_p$s/$p8 ]; then
      sr+=("$r"); sp8+=("$O/${sp}_p$s/$p8=$P8"); ss+=("$d/$s8=$P8, shapes varied 0.3")
    fi
    # the same seed's real only retrained on the shape cell's machine (../adaboost_critic/run2.sh real eN N): the
    # shape cell against it, and real only there against real only here (the machine alone)
    e=$H/${sp}_e$s/$real; [ -f $e ] || continue
    he+=("$e=real only, retrained on the shape cell's machine"); hs+=("$d/$s8=$P8, shapes varied 0.3")
    ht+=("${r%%=*}=real only, stored (stops 86-89's machine)")
  done
  [ ${#ss[@]} -gt 0 ] && python $T "${sr[@]}" "${sp8[@]}" "${ss[@]}" --out $O/${sp}_shapes_vs_real.md
  [ ${#ss[@]} -gt 0 ] && python $T "${sp8[@]}" "${ss[@]}" --out $O/${sp}_shapes_vs_pose.md
  [ ${#he[@]} -gt 0 ] && python $T "${he[@]}" "${hs[@]}" --out $O/${sp}_shapes_vs_real_same_machine.md
  [ ${#he[@]} -gt 0 ] && python $T "${ht[@]}" "${he[@]}" --out $O/${sp}_real_only_two_machines.md
done
# stop 91: the pose cell retrained on the shape cell's machine (run.sh mN N --quantize on --pose-sampling
# fitted_at_seed), so that real only, the pose cell and the shape cell of a seed all come from one machine; and the
# pose cell on the two machines (the machine alone, as for real only above)
for sp in val test; do
  me=(); mp=(); ms=(); ps=(); pm=()
  for d in $O/${sp}_m[0-9]*; do
    s=${d##*_m}; [ -f $d/$p8 ] || continue
    if [ -f $O/${sp}_p$s/$p8 ]; then
      ps+=("$O/${sp}_p$s/$p8=$P8, stored (stops 86-89's machine)")
      pm+=("$d/$p8=$P8, retrained on the shape cell's machine")
    fi
    e=$H/${sp}_e$s/$real; [ -f $e ] && [ -f $O/${sp}_s$s/$s8 ] || continue
    me+=("$e=real only"); mp+=("$d/$p8=$P8"); ms+=("$O/${sp}_s$s/$s8=$P8, shapes varied 0.3")
  done
  [ ${#me[@]} -gt 0 ] && python $T "${me[@]}" "${mp[@]}" "${ms[@]}" --out $O/${sp}_one_machine.md
  [ ${#me[@]} -gt 0 ] && python $T "${mp[@]}" "${ms[@]}" --out $O/${sp}_shapes_vs_pose_one_machine.md
  [ ${#pm[@]} -gt 0 ] && python $T "${ps[@]}" "${pm[@]}" --out $O/${sp}_pose_two_machines.md
done
# stop 92: the shape cell against real only on every seed that has both on the one machine (seeds 4 on: real only by
# ../adaboost_critic/run2.sh real eN N, the shape cell by run.sh sN N as above; no pose cell trained for them)
for sp in val test; do
  ae=(); as=()
  for d in $O/${sp}_s[0-9]*; do
    s=${d##*_s}; e=$H/${sp}_e$s/$real; [ -f $d/$s8 ] && [ -f $e ] || continue
    ae+=("$e=real only"); as+=("$d/$s8=$P8, shapes varied 0.3")
  done
  [ ${#as[@]} -gt 0 ] && python $T "${ae[@]}" "${as[@]}" --out $O/${sp}_shapes_one_machine_all_seeds.md
done
