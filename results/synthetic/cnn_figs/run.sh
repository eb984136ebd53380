#!/usr/bin/env bash
# Issue 16: the paper's Figs. 9-11 for the CNN (library defaults: ensemble box map, fine-tuned on the real seeds after
# the synthetic ones), and the added positives' share, protocol halmstad_v2, 100 real seeds + synthetic from each
# training seed's d_HOG fit, test split, 5 training seeds; the baseline cells (real only, 20x with every effect) are
# read back from ../cnn_finetune/. Queue B and C may run at once (distinct cells).
# usage (repository root): results/synthetic/cnn_figs/run.sh B|C
set -euo pipefail
D=results/synthetic/cnn_figs; R=results/synthetic/run_100.sh; S="0 1 2 3 4"
case $1 in
  B) $R cnn $D/share25 test "$S" --synthetic-share 0.25
     $R cnn $D/capture_uniform test "$S" --capture-sampling uniform
     $R cnn $D/effects_off_a test "$S" --effects-off object_noise motion_blur ;;
  C) $R cnn $D/ratio5 test "$S" --synthetic-ratios 5
     $R cnn $D/effects_off_b test "$S" --effects-off boundary_blur material ;;
esac
