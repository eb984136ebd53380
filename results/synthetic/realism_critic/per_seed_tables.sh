#!/bin/bash
# Stop 83: the tables of the per-seed selection (run_seed.sh 12 0..9, run_seed.sh 100 0..9), from the stored results.
# usage (from the repository root): results/synthetic/realism_critic/per_seed_tables.sh  (trains nothing; ~1 min)
O=results/synthetic/realism_critic
T=results/learning_curve/video_diversity/table.py
export PYTHONPATH=${PYTHONPATH:-.}
for n in 12 100; do
  D=$O/per_seed_$n
  real=hog_${n}_seeds.json every=hog_${n}_seeds_20x_synthetic_hog.json
  set=hog_${n}_seeds_20x_synthetic_hog_the_25_least_synthetic_of_4x_drawn.json
  seed=hog_${n}_seeds_20x_synthetic_hog_the_25_least_synthetic_of_4x_drawn_of_each_seed.json
  seeds=$(ls -d $D/test_*/ | sed 's/.*test_//; s/\/$//' | sort -n)
  for sp in test val; do
    rows() { for c in "$@"; do for s in $seeds; do echo "$D/${sp}_$s/${!c}=$c"; done; done; }
    python $T $(rows every real set seed) --out $D/${sp}_vs_every_draw.md
    python $T $(rows set seed) --out $D/${sp}_seed_vs_set.md
    python $T $(rows real every set seed) --out $D/${sp}_vs_real.md
    if [ $n = 12 ]; then
      list() { for s in $seeds; do printf "%s," "$1/${sp}_$s/$2"; done | sed 's/,$//'; }
      python results/synthetic/gap_closed.py --few $(list $D $real) --added $(list $D $every) --added $(list $D $set) \
        --added $(list $D $seed) --many $(list $O/per_seed_100 hog_100_seeds.json) --out $D/gap_closed_$sp.md
    fi
  done
done
