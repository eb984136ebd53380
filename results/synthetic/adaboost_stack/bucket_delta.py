"""Paired AP@0.5 differences per size bucket: each condition against a baseline, same seeds and video resamples.

usage: PYTHONPATH=. python results/synthetic/adaboost_stack/bucket_delta.py BASELINE.json CONDITION.json [...]
"""
import sys

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import paired_difference


def main(argv: list[str]) -> None:
    if len(argv) < 2:
        raise SystemExit(__doc__)
    base = ProtocolResult.load(argv[0])
    for path in argv[1:]:
        cond = ProtocolResult.load(path)
        cells = []
        for i, b in enumerate(base.protocol.size_buckets):
            if base.n_objects(i) == 0:
                continue
            d = paired_difference(base.pools(None, i), cond.pools(None, i)).difference
            hi = "" if b.high is None else f"{b.high:g}"
            cells.append(f"{b.low:g}-{hi} px ({base.n_objects(i)}): {d.estimate:+.3f} [{d.low:+.3f}, {d.high:+.3f}]")
        print(f"{cond.condition}: " + " | ".join(cells))


if __name__ == "__main__":
    main(sys.argv[1:])
