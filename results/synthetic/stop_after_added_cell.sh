#!/bin/bash
# A runner call stopped once its log shows PATTERN (the added cell's "cell done" line: the runner trains real only
# after the added cells, and the callers have that cell stored), its JSON then written from the cell cache by the
# same call with --read-only appended. Output of both goes to LOG (emptied first).
# usage (repository root): results/synthetic/stop_after_added_cell.sh LOG PATTERN COMMAND [ARGUMENTS...]
#   SEED_COUNT=100 results/synthetic/stop_after_added_cell.sh $A/native100_s1.log "synthetic.*cell done" \
#     $A/run.sh recipe 1 $A/native100_s1        (A=results/synthetic/airplane_v2/adaboost_recipe)
log=$1; pattern=$2; shift 2
: > "$log"
"$@" >> "$log" 2>&1 &
pid=$!
while kill -0 $pid 2>/dev/null; do
  if grep -q "$pattern" "$log" 2>/dev/null; then
    kids=$(pgrep -P $pid)  # the call first (a wrapper script must not go on), then what it had started
    kill $pid; [ -z "$kids" ] || kill $kids 2>/dev/null
    break
  fi
  sleep 15
done
wait $pid
"$@" --read-only >> "$log" 2>&1
