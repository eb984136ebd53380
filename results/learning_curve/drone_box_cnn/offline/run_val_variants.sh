#!/bin/bash
# choose the box regressor's jitter on the VALIDATION split (dumped raw detections of one detector per family)
cd "$(dirname "$0")/../../../.."; mkdir -p data/analysis/x2
K=${1:-hog}
OMP_NUM_THREADS=1 python results/learning_curve/drone_box_cnn/offline/reg_variants.py $K '{"s.35": dict(scales=(1.0,), sig=0.35), "s.5": dict(scales=(1.0,), sig=0.5), "s.6": dict(scales=(1.0,), sig=0.6), "s.75": dict(scales=(1.0,), sig=0.75), "s.5 shift.2": dict(scales=(1.0,), sig=0.5, shift=0.2), "s.5 scales1-2": dict(scales=(1.0, 1.5, 2.0), sig=0.5)}' val val
