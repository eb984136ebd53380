#!/bin/bash
# the two fits of results/diagnose/texture/README.md (same code, budget and init)
set -e
F="synthaug fit --seeds data/halmstad/seedsets/drone_100 --mesh ../shared/data/meshes/quadcopter.glb --distance hog --budget 1500 --workers 2 --no-progress"
/usr/bin/time -f "texture fit wall %e s" $F --effects material motion_blur boundary_blur object_noise object_texture \
    --out results/diagnose/texture/drone_100_hog_texture.json
/usr/bin/time -f "base fit wall %e s" $F --effects material motion_blur boundary_blur object_noise \
    --out results/diagnose/texture/drone_100_hog_base.json
