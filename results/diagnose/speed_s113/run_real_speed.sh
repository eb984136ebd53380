#!/usr/bin/env bash
# The real drone and airplane reports' diagnosis time before and after stop 113 (frame evidence, JPEG on each seed's
# own canvas), alternating, one thread, on the stored ingest and the committed HOG fits of results/diagnose/run_real.sh.
# BASE: a checkout of the code before. Usage: BASE=/work/base bash results/diagnose/speed_s113/run_real_speed.sh
set -euo pipefail
export OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl
root=$PWD
out=$root/results/diagnose/speed_s113/real
mkdir -p "$out"
for rep in 1 2; do
  for which in before after; do
    pp=$([ "$which" = before ] && echo "$BASE" || echo "$PWD")
    for obj in drone:quadcopter airplane:twin_prop_airplane; do
      name=${obj%%:*}; mesh=${obj##*:}
      # run from the code's own root: `python -m` puts the working directory first on the path
      (cd "$pp" && python -m synthaug.cli diagnose --seed-set "$root/data/halmstad/seedsets/${name}_100" \
        --mesh "$root/../shared/data/meshes/$mesh.glb" --params "$root/results/paper/fits/${name}_100_hog.json" \
        --distance hog --out /tmp/s113_real_${which}_$name --no-progress) | sed "s/^/$which $rep $name /" \
        | tee -a "$out/times.log"
    done
  done
done
