"""Issue 15: does a detector learn from more frames of the same videos, or from more videos? One table.

Each row is a stored ``ProtocolResult`` (runner JSON; files of one condition are combined), the first the paired
baseline. Columns: the positives and the videos they come from, AP@0.5 and AP@0.3 with their 95 % CIs (bootstrap
over test videos, seeds inside), and the paired difference to the baseline at both IoUs (same seeds, same resamples),
then the AP@0.5 difference's interval with the training seeds resampled too (``paired_difference(resample_seeds=True)``:
training randomness counted; coarse under 5 seeds).

    PYTHONPATH=. python results/learning_curve/video_diversity/table.py BASELINE.json OTHER.json [...] [--out MD]
    # FILE=LABEL names a row (e.g. one condition trained with other options)
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from synthaug.evaluate.stats import bootstrap_seed_mean, paired_difference
from synthaug.evaluate.summary import other_machine_note

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "unlabelled_drones"))
from rescore import load_conditions  # noqa: E402  (one loader of stored results per condition)


def _iv(x) -> str:
    return f"{x.estimate:.3f} [{x.low:.3f}, {x.high:.3f}]"


def _d(x) -> str:
    return f"{x.estimate:+.3f} [{x.low:+.3f}, {x.high:+.3f}]"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", nargs="+")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    # FILE=LABEL names a row (two runs of one condition under other options)
    files, _, labels = zip(*(arg.partition("=") for arg in a.results))
    res = load_conditions(list(files), [label or None for label in labels])
    base_name = next(iter(res))
    base = res[base_name]
    p = base.protocol
    kw = dict(resamples=p.bootstrap.resamples, seed=p.bootstrap.seed, ci=p.bootstrap.ci)
    lines = ["| condition | seeds | positives (mean) | positive videos | AP@0.5 [95 % CI] | AP@0.3 [CI] | "
             f"Δ AP@0.5 vs {base_name} [CI] | Δ AP@0.3 [CI] | videos improved (0.5) | "
             "Δ AP@0.5 CI, seeds resampled too |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    apart = {}  # row -> seeds trained on another machine than the baseline's of the same id
    for name, r in res.items():
        assert r.protocol.fingerprint() == p.fingerprint() and r.stems == base.stems, name
        pos = [sr.meta.get("positives") for sr in r.seeds.values() if sr.meta.get("positives")]
        k = r.meta.get("condition", {}).get("positive_videos")
        cells = [name, str(len(r.seeds)), f"{np.mean(pos):.0f}" if pos else "–", "all" if k is None else str(k),
                 _iv(bootstrap_seed_mean(r.pools(0.5), **kw)), _iv(bootstrap_seed_mean(r.pools(0.3), **kw))]
        if r is base:
            cells += ["(baseline)", "", "", ""]
        else:
            d5 = paired_difference(base.pools(0.5), r.pools(0.5), stems=r.stems, **kw)
            d3 = paired_difference(base.pools(0.3), r.pools(0.3), stems=r.stems, **kw)
            ds = paired_difference(base.pools(0.5), r.pools(0.5), stems=r.stems, resample_seeds=True, **kw).difference
            apart[name] = sorted(s for s in r.trained_elsewhere(base) if s in d5.seeds)
            cells += [_d(d5.difference) + (" †" if apart[name] else ""), _d(d3.difference),
                      f"{d5.wins.improved}/{d5.wins.improved + d5.wins.worse + d5.wins.tied}",
                      f"[{ds.low:+.3f}, {ds.high:+.3f}]"]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", f"Protocol `{p.name}` (fingerprint `{p.fingerprint()}`), split `{base.split}`, {len(base.stems)} test "
              f"videos; {p.bootstrap.resamples} bootstrap resamples of the videos (seed {p.bootstrap.seed}); Δ paired "
              "by training seed and resample; the last column resamples the training seeds as well (pairs kept)."]
    note = other_machine_note(apart)
    if note:
        lines.append(note)
    text = "\n".join(lines)
    print(text)
    if a.out:
        Path(a.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
