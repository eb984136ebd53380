#!/bin/bash
# One run.sh call at 100 seeds stopped once its added (synthetic) cell is done, its JSON then written from the cell
# cache by the same call with --read-only: the 100-real cell it would train next is stored (real100_sSEED).
# usage (repository root): results/synthetic/airplane_v2/adaboost_recipe/run_stopped.sh LOG run.sh-arguments...
#   run_stopped.sh $A/native100_s1.log recipe 1 $A/native100_s1
#   run_stopped.sh $A/eightbit100_s1.log recipe 1 $A/eightbit100_s1 --quantize on
log=$1; shift
A=results/synthetic/airplane_v2/adaboost_recipe
: > "$log"
SEED_COUNT=100 $A/run.sh "$@" >> "$log" 2>&1 &
pid=$!
while kill -0 $pid 2>/dev/null; do
  if grep -q "synthetic.*cell done" "$log"; then pkill -P $pid; kill $pid; break; fi
  sleep 15
done
wait $pid
SEED_COUNT=100 $A/run.sh "$@" --read-only >> "$log" 2>&1
echo "stopped-cell done $(date)" >> "$log"
