#!/bin/bash
# issue 20: the power of the calibrated floors, 5 fresh nuisance-varied cases per candidate at its realistic
# strength (REALISTIC_STRENGTHS), the tests' converged fit; EFFECTS="..." picks a subset (two shells split the list).
cd "$(dirname "$0")/../../.."
export OMP_NUM_THREADS=1
for e in ${EFFECTS:-vignetting gamma shot_noise defocus compression specular haze chromatic_aberration white_balance sharpening lens_distortion rolling_shutter rotor_blur exposure}; do
  c=${COLOUR:+_colour}${ALT:+_alt}
  /usr/bin/time -f "$e$c: wall %e s" python benchmarks/bench_diagnose_null.py --cases 5 --base-seed 8000 --hidden $e \
    ${COLOUR:+--colour} ${ALT:+--strength alt} --workdir outputs/bench_diagnose_power5_$e$c \
    --out results/diagnose/null/power5_$e$c.json > /dev/null
done
# the colour effects again on colour cases (COLOUR=1): EFFECTS="chromatic_aberration white_balance haze" COLOUR=1
# the second realistic strength (ALT=1: bench_diagnose_null.py --strength alt)
