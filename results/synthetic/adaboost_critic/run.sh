#!/bin/bash
# Stop 86: AdaBoost, drones, 100 seeds: real only, then + 20x synthetic with the HOG realism critic (each seed keeps the
# quarter of its own draws it finds least synthetic), in one runner call per split (README.md).
# usage (repository root): results/synthetic/adaboost_critic/run.sh TAG SEED KEEP...   (= run2.sh both TAG SEED KEEP...)
exec "$(dirname "$0")/run2.sh" both "$@"
