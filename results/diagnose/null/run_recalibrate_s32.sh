#!/bin/bash
# Stop 32: the null calibration rerun after the frames' blockiness became the smaller of its column and row values
# (a codec's square blocks lift both directions; a sensor's fixed column pattern one: at sd 0.04 it was named
# compression (frame) in 1 of 5 power cases). The same four calibration and fresh sets, seeds, fits and steps as
# stop 30, regenerated on this machine: run_recalibrate_s30.sh itself.
exec bash "$(dirname "$0")/run_recalibrate_s30.sh" "$@"
