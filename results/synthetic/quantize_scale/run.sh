#!/bin/bash
# stop 106: measure.py on the seed sets the runner made this stop (drones 100, training seeds 0-2; airplanes 12, seed 2)
# usage (repository root, after the runner's ingests and fits): results/synthetic/quantize_scale/run.sh  (~40 s a set)
export OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl PYTHONPATH=.
M=results/synthetic/quantize_scale
python $M/measure.py data/runs/ingest_airplane_seed2/seedsets/airplane_12 \
  data/runs/fits/airplane_12_seed2_hog_twin_prop_airplane.json ../shared/data/meshes/twin_prop_airplane.glb \
  1.25 1.0 0.8 0.64 0.51 0.41 0.33 0.26 > $M/airplane_12_seed2.md
for s in 0 1 2; do
  python $M/measure.py data/runs/ingest_drone_seed$s/seedsets/drone_100 \
    data/runs/fits/drone_100_seed${s}_hog_quadcopter.json ../shared/data/meshes/quadcopter.glb \
    1.25 1.0 0.8 0.64 0.51 0.41 > $M/drone_100_seed$s.md
done
