#!/bin/bash
# Stop 30: every power run again under the recalibrated floors (the frame channels changed the Bonferroni count and
# every floor): both realistic strengths of each gray candidate and outside effect, the colour effects on colour
# cases; two shells side by side (2 cores). Then the table: python results/diagnose/null/power_table.py
cd "$(dirname "$0")/../../.."
P=results/diagnose/null/run_power5.sh
L=results/diagnose/null
run() { EFFECTS="$1" bash $P; EFFECTS="$1" ALT=1 bash $P; }
date -u
( run "vignetting compression specular sharpening lens_distortion column_pattern" 2>&1
  EFFECTS="chromatic_aberration white_balance haze" COLOUR=1 bash $P 2>&1 ) > $L/power_s30_a.log &
( run "gamma shot_noise defocus exposure rolling_shutter rotor_blur interlacing" 2>&1
  EFFECTS="chromatic_aberration white_balance haze" COLOUR=1 ALT=1 bash $P 2>&1 ) > $L/power_s30_b.log &
wait
date -u
