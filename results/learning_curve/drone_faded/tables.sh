#!/usr/bin/env bash
# usage: tables.sh SPLIT FAMILY COPIES   (the 3 seeds' cells paired, trains nothing; see ../added_positives.sh)
exec bash "$(dirname "$0")/../added_positives.sh" tables --faded-copies results/learning_curve/drone_faded "$@"
