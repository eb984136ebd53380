#!/bin/bash
# Stop 32: the power runs under the floors of run_recalibrate_s32.sh (blockiness = the smaller of columns and rows),
# both realistic strengths; the runs the change touches first (compression, column_pattern), then the rest, then the
# colour effects on colour cases; two shells side by side (2 cores). Table: python results/diagnose/null/power_table.py
cd "$(dirname "$0")/../../.."
P=results/diagnose/null/run_power5.sh
L=results/diagnose/null
run() { for e in $1; do EFFECTS="$e" bash $P; EFFECTS="$e" ALT=1 bash $P; done; }
date -u
( run "compression vignetting lens_distortion specular sharpening rotor_blur interlacing" 2>&1
  EFFECTS="chromatic_aberration white_balance haze" COLOUR=1 bash $P 2>&1 ) > $L/power_s32_a.log &
( run "column_pattern gamma shot_noise defocus exposure rolling_shutter" 2>&1
  EFFECTS="chromatic_aberration white_balance haze" COLOUR=1 ALT=1 bash $P 2>&1 ) > $L/power_s32_b.log &
wait
date -u
