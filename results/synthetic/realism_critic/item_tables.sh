#!/bin/bash
# Stop 84: the tables of the critic's lazy form (run_item.sh 12 ...), from the stored results.
# usage (from the repository root): results/synthetic/realism_critic/item_tables.sh  (trains nothing; ~1 min)
O=results/synthetic/realism_critic
T=results/learning_curve/video_diversity/table.py
export PYTHONPATH=${PYTHONPATH:-.}
D=$O/per_item_12
real=hog_12_seeds.json
seed=hog_12_seeds_20x_synthetic_hog_the_25_least_synthetic_of_4x_drawn_of_each_seed.json
item=hog_12_seeds_20x_synthetic_hog_the_least_synthetic_of_4_candidates_per_patch.json
seeds=$(ls -d $D/test_*/ | sed 's/.*test_//; s/\/$//' | sort -n)
for sp in test val; do
  rows() { for c in "$@"; do for s in $seeds; do echo "$D/${sp}_$s/${!c}=$c"; done; done; }
  python $T $(rows seed item) --out $D/${sp}_item_vs_seed.md
  python $T $(rows real seed item) --out $D/${sp}_vs_real.md
done
