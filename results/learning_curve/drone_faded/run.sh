#!/usr/bin/env bash
# usage: run.sh SPLIT FAMILY COPIES SEED   (one training seed; see ../added_positives.sh)
exec bash "$(dirname "$0")/../added_positives.sh" run --faded-copies results/learning_curve/drone_faded "$@"
