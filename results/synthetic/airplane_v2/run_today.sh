#!/usr/bin/env bash
# Stop 85: the airplanes' HOG table under today's HOG defaults (box calibration on every 20th training frame, the
# realism critic's least synthetic quarter of a 4x draw of each seed), which the tables above predate: real only,
# + 20x synthetic, + 20x perturbed, + 20x copy-paste; 100 seeds, test split. run.sh's pins (--effects-off none,
# --background-sampling seed, ...) are HOG's defaults anyway; AdaBoost- and CNN-only pins do not touch HOG cells.
# usage (repository root; one job per seed list, the cells are cached in data/runs/cells):
#   results/synthetic/airplane_v2/run_today.sh SEED...            100 seeds: the four conditions
#   results/synthetic/airplane_v2/run_today.sh twelve SEED...     12 seeds: real only and + 20x synthetic
#   results/synthetic/airplane_v2/run_today.sh fitted SEED...     100 seeds: + 20x synthetic at fitted poses
#   results/synthetic/airplane_v2/run_today.sh tables SEED...     reads the cells back, writes the tables
#   results/synthetic/airplane_v2/run_today.sh val SEED...        the same detectors on the validation videos
set -euo pipefail
A=results/synthetic/airplane_v2
T=results/learning_curve/video_diversity/table.py
export PYTHONPATH=${PYTHONPATH:-.}
SYN=hog_100_seeds_20x_synthetic_hog_twin_prop_airplane_the_25_least_synthetic_of_4x_drawn_of_each_seed.json
FIT=hog_100_seeds_20x_synthetic_hog_twin_prop_airplane_fitted_poses_the_25_least_synthetic_of_4x_drawn_of_each_seed.json
fitted_vs_uniform() {  # UNIFORM_DIR FITTED_DIR: the paired table of the two pose samplings, into FITTED_DIR
  python $T "$1/$SYN=+20x synthetic, uniform poses" "$2/$FIT=+20x synthetic, fitted poses" \
    --out $2/fitted_vs_uniform.md > /dev/null
}
mode=full
case "$1" in twelve|fitted|tables|val) mode=$1; shift;; esac
if [ $mode = val ]; then
  $A/run.sh hog hog_100_today_val "$*" --pose-sampling uniform fitted --eval-split val
  fitted_vs_uniform $A/hog_100_today_val $A/hog_100_today_val
  exit 0
fi
if [ $mode = tables ]; then
  seeds="$*"
  export LOG_SUFFIX=_tables
  $A/run.sh hog hog_100_today "$seeds" --perturb-copies 20 --copy-paste-ratios 20
  $A/run.sh hog hog_12_today "$seeds" --seed-counts 12
  $A/run.sh hog hog_100_today_fitted "$seeds" --pose-sampling fitted
  D=$A/hog_100_today; D12=$A/hog_12_today; DF=$A/hog_100_today_fitted
  python $T "$D/hog_100_seeds_20x_perturbed.json=+20x perturbed" "$D/$SYN=+20x synthetic" \
    --out $D/synthetic_vs_perturbed.md > /dev/null
  python $T "$D/hog_100_seeds_20x_copy_paste_hog_twin_prop_airplane_silhouettes.json=+20x copy-paste" \
    "$D/$SYN=+20x synthetic" --out $D/synthetic_vs_copy_paste.md > /dev/null
  fitted_vs_uniform $D $DF
  python results/synthetic/gap_closed.py --few $D12/hog_12_seeds.json --added $D12/${SYN/100/12} \
    --many $D/hog_100_seeds.json --title "airplanes, HOG, today's defaults" --out $D12/gap_closed.md
  exit 0
fi
for s in "$@"; do
  t0=$(date +%s)
  case $mode in
    full) $A/run.sh hog hog_100_today_s$s "$s" --perturb-copies 20 --copy-paste-ratios 20;;
    twelve) $A/run.sh hog hog_12_today_s$s "$s" --seed-counts 12;;
    fitted) $A/run.sh hog hog_100_today_fitted_s$s "$s" --pose-sampling fitted;;
  esac
  echo "$mode, seed $s: $(( $(date +%s) - t0 )) s" >> $A/hog_100_today_times.txt
done
