#!/usr/bin/env bash
# Stop 114: the power tables with this stop's rows (defocus_s114/BASE) over stop 112's (its dir lists, each set's);
# usage: bash tables.sh [STOP]   STOP=112 leaves this stop's rows out (stop 112's tables, to check the lists)
set -euo pipefail
cd "$(dirname "$0")/../../../.."
n=results/diagnose/null
for base in 8000 13000 11000; do
  case $base in
    8000) dirs="$n $n/periodic_s96/8000 $n/centre_s100/8000 $n/objects_s100/8000";;
    13000) dirs="$n/clip_s99/13000 $n/centre_s100/13000 $n/objects_s100/13000";;
    11000) dirs="$n/fresh11000 $n/periodic_s96/11000 $n/clip_s99/11000 $n/centre_s100/11000 $n/objects_s100/11000";;
  esac
  dirs="$dirs $n/highlight_s110/$base $n/highlight_s111/$base $n/highlight_s112/video_light/$base"
  if [ "${1:-114}" = 112 ]; then
    PYTHONPATH=. python $n/power_table.py $dirs
  else
    PYTHONPATH=. python $n/power_table.py $dirs $n/defocus_s114/$base > $n/defocus_s114/${base}_table.md
  fi
done
