"""Issue 16: compare two added-positive conditions trained on two machines, each against its own machine's real-only
cells (cells do not reproduce across machines, so a direct pairing would carry the machines' offset).

Difference in differences, AP@0.5 and AP@0.3, mean over training seeds, percentile bootstrap over the test videos with
the protocol's resamples (the same resample for all four results):
    (B - A) - (D - C),  A, B: real only and a condition on machine 1;  C, D: the same on machine 2.

    PYTHONPATH=. python results/synthetic/adaboost_baselines/across_machines.py A.json B.json C.json D.json [--out MD]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import bootstrap_statistic, seed_mean_samples


def did(results: list[ProtocolResult], iou: float) -> tuple[float, float, float, float]:
    """``(estimate, low, high, share of resamples > 0)`` of ``(B - A) - (D - C)`` at ``iou``."""
    base = results[0]
    p = base.protocol
    for r in results:
        if r.protocol.fingerprint() != p.fingerprint() or r.stems != base.stems:
            raise ValueError(f"{r.condition!r} was scored under another protocol or on other videos")
    pools = [r.pools(iou) for r in results]

    def statistic(counts: np.ndarray) -> float:
        a, b, c, d = (float(seed_mean_samples(pool, counts[None])[0]) for pool in pools)
        return (b - a) - (d - c)

    iv = bootstrap_statistic(statistic, len(base.stems), resamples=p.bootstrap.resamples, seed=p.bootstrap.seed,
                             ci=p.bootstrap.ci)
    return iv.estimate, iv.low, iv.high, float(np.mean(iv.samples > 0))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", nargs=4, metavar="JSON", help="A B C D (see the module's docstring)")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    res = [ProtocolResult.load(f) for f in a.results]
    lines = ["| IoU | (B − A) − (D − C) [95 % CI] | resamples > 0 |", "|---|---|---|"]
    for iou in (0.5, 0.3):
        est, lo, hi, share = did(res, iou)
        lines.append(f"| {iou:g} | {est:+.3f} [{lo:+.3f}, {hi:+.3f}] | {share:.2f} |")
    names = "; ".join(f"{k} = {Path(f).parent.name}/{Path(f).name} ({len(r.seeds)} seeds)"
                      for k, f, r in zip("ABCD", a.results, res))
    lines += ["", names, f"Protocol `{res[0].protocol.name}`, {len(res[0].stems)} test videos, "
              f"{res[0].protocol.bootstrap.resamples} resamples (seed {res[0].protocol.bootstrap.seed})."]
    text = "\n".join(lines)
    print(text)
    if a.out:
        Path(a.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
