# The stored Intel Xeon cells of AdaBoost on the drones at 100 seeds (test split, calibrated), by training seed: real
# only and AdaBoost's recipe (8-bit, 5 soft distractors per seed). Sourced by the tables scripts that pair against them.
# usage: . results/synthetic/adaboost_distractors/stored_cells.sh; stored_cells S   (sets real_dir and recipe_dir)
stored_cells() {
  local D=results/synthetic/adaboost_distractors
  case $1 in
    0|1) real_dir=$D/intel_cal_test/seed$1 recipe_dir=$D/frame_s102/soft5/seed$1;;
    2) real_dir=$D/frame_s101/seed2 recipe_dir=$D/frame_s102/soft5/seed2;;
    *) real_dir=$D/frame_s103/new_seeds/seed$1 recipe_dir=$real_dir;;
  esac
}
