"""The runner's ``synthetic`` command without its real-only cell: for a second process that trains a seed's added
condition while another trains the same seed's real-only cell (each runner call otherwise runs the real-only cell
first and would wait on the other's lock). Same arguments as ``python -m synthaug.evaluate.runner synthetic``; the
real-only row is then missing from this call's own comparison.md, and the tables come from ``tables.sh``.

usage (repository root): python results/synthetic/adaboost_critic/added_only.py synthetic --protocol ... --out OUT
"""
import sys

import synthaug.evaluate.runner as R

_run_into = R._run_into


def _added_only(results, runner, condition, seeds, **kw):
    if condition == R.Condition(condition.name, condition.kind, seed_count=condition.seed_count):
        return None  # the real-only condition: nothing added, every other field at its default
    return _run_into(results, runner, condition, seeds, **kw)


R._run_into = _added_only

if __name__ == "__main__":  # the ingest's spawned workers import this file again: they must not run the runner
    sys.exit(R.main(sys.argv[1:]))
