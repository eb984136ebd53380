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
    p = base.protocol
    kw = dict(resamples=p.bootstrap.resamples, seed=p.bootstrap.seed, ci=p.bootstrap.ci)  # as table.py
    for path in argv[1:]:
        cond = ProtocolResult.load(path)
        if cond.protocol.fingerprint() != p.fingerprint() or cond.stems != base.stems:
            raise SystemExit(f"{path}: another protocol or other videos than {argv[0]}; the pairs would not hold")
        cells = []
        for i, b in enumerate(p.size_buckets):
            n = base.n_objects(i)
            if n == 0:
                continue
            d = paired_difference(base.pools(0.5, i), cond.pools(0.5, i), stems=base.stems, **kw).difference
            hi = "" if b.high is None else f"{b.high:g}"
            cells.append(f"{b.low:g}-{hi} px ({n}): {d.estimate:+.3f} [{d.low:+.3f}, {d.high:+.3f}]")
        print(f"{cond.condition}: " + " | ".join(cells))


if __name__ == "__main__":
    main(sys.argv[1:])
