#!/bin/bash
# Stop 86: the tables of AdaBoost with the realism critic, from whatever cells run.sh / run2.sh have stored
# (c<seed>: real only + critic, one runner call; r<seed>/c<seed> from run2.sh: the same two cells in two calls;
# a<seed>: every draw). Trains nothing (~1 min).
# usage (repository root): results/synthetic/adaboost_critic/tables.sh
O=results/synthetic/adaboost_critic
T=results/learning_curve/video_diversity/table.py
export PYTHONPATH=${PYTHONPATH:-.}
real=adaboost_100_seeds.json
critic=adaboost_100_seeds_20x_synthetic_hog_quadcopter_share_0.25_the_25_least_synthetic_of_4x_drawn_of_each_seed.json
every=adaboost_100_seeds_20x_synthetic_hog_quadcopter_share_0.25.json
for sp in val test; do
  rows=(); crit=(); evr=(); seen=" "
  for d in $O/${sp}_[rc][0-9]*; do  # one real-only file a seed (stop 88: r2 and c2 both hold seed 2's, one cell)
    s=${d##*_[rc]}
    [ -d $O/${sp}_c$s ] || continue  # seeds with a critic cell (r3: real only for ../adaboost_wl_critic's q3)
    [ -f $d/$real ] && [[ "$seen" != *" $s "* ]] && rows+=("$d/$real=real only") && seen="$seen$s "
  done
  for d in $O/${sp}_c[0-9]*; do [ -f $d/$critic ] && crit+=("$d/$critic=+ 20x synthetic, critic keeps 1/4"); done
  for d in $O/${sp}_a[0-9]*; do [ -f $d/$every ] && evr+=("$d/$every=+ 20x synthetic, every draw"); done
  python $T "${rows[@]}" "${crit[@]}" "${evr[@]}" --out $O/${sp}_vs_real.md
  [ ${#evr[@]} -gt 0 ] && python $T "${evr[@]}" "${crit[@]}" --out $O/${sp}_critic_vs_every_draw.md
done
