"""Stored protocol results (halmstad_v1, test split) re-scored without the test videos whose drone is unlabelled.

V_DRONE_106 and V_DRONE_107 have a null label in every frame and V_DRONE_108 in 217 of 305, while the drone is in
view (``top_detections_106_107_108.png``); under v1 every detection of them is a false positive. Protocol v2
(``configs/protocol/halmstad_v2.json``) skips frames without a labelled box; a stored result keeps matches per video,
not per frame, so here the three videos are dropped whole (V_DRONE_108's 88 labelled frames with them): an
approximation of v2 from results already computed, with the bootstrap over the 13 remaining videos.

    PYTHONPATH=. python results/learning_curve/unlabelled_drones/rescore.py BASELINE.json OTHER.json [...] [--out MD]
    # one table of all the videos the results hold, nothing dropped (e.g. two runner invocations' v2 cells):
    PYTHONPATH=. python results/learning_curve/unlabelled_drones/rescore.py BASELINE.json OTHER.json --keep-all

Each file: a ``ProtocolResult`` JSON (``runner`` tables' per-condition files; files of the same condition, e.g. one
per training seed, are combined); the first condition is the paired baseline.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.summary import report_table

UNLABELLED = ("V_DRONE_106", "V_DRONE_107", "V_DRONE_108")


def without(res: ProtocolResult, stems: tuple[str, ...] = UNLABELLED) -> ProtocolResult:
    out = ProtocolResult(res.condition, res.protocol, res.split, res.scale, {}, dict(res.meta))
    for seed, sr in res.seeds.items():
        out.add_seed(seed, videos=[v for v in sr.videos if v.stem not in stems],
                     patches=[p for p in sr.patches if p.stem not in stems], meta=sr.meta)
    return out


def load_conditions(files: list[str], labels: list[str | None] | None = None) -> dict[str, ProtocolResult]:
    """Stored results, one row per condition in the order given: files of one condition (e.g. one per training
    seed) are combined; ``labels[i]``, when given, names file ``i``'s row instead of its condition."""
    by_cond: dict[str, list[ProtocolResult]] = {}
    for f, label in zip(files, labels or [None] * len(files)):
        r = ProtocolResult.load(f)
        by_cond.setdefault(label or r.condition, []).append(r)
    return {cond: ProtocolResult.combine(parts) for cond, parts in by_cond.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", nargs="+")
    ap.add_argument("--out", default=None)
    ap.add_argument("--keep-all", action="store_true", help="one table of every video the results hold, nothing dropped")
    a = ap.parse_args()
    combined = load_conditions(a.results)
    first = next(iter(combined))
    if a.keep_all:
        text = report_table(combined, baseline=first)
    else:
        lines = [f"Baseline of the paired rows: {first} on the same videos.", ""]
        for tag, pick in (("16 videos", lambda r: r), ("13 videos", without)):
            sub = {f"{c} ({tag})": pick(r) for c, r in combined.items()}
            lines += [f"### {tag}", "", report_table(sub, baseline=f"{first} ({tag})"), ""]
        text = "\n".join(lines)
    print(text)
    if a.out:
        Path(a.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
