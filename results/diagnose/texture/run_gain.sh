#!/bin/bash
# AP on the real test videos: new base fit vs texture fit (results/diagnose/texture/README.md)
python -m synthaug.diagnose.gain --class drone --training-seeds ${SEEDS:-0 1 2} \
    --fit results/diagnose/texture/drone_100_hog_base.json \
    --extended-fit results/diagnose/texture/drone_100_hog_texture.json \
    --cells results/diagnose/texture/cells.json --out results/diagnose/texture/gain
