"""Where do AdaBoost's synthetic positives gain and lose at 100 seeds? Every stored AdaBoost test cell beside its
own seed's real-only cell: the recall ceiling, the precision over the recall both reach, AP per size bucket and per
test video (stored results only; nothing is retrained).

    PYTHONPATH=. python results/synthetic/adaboost_where/where.py > results/synthetic/adaboost_where/where.txt
"""
from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np

from synthaug.evaluate.ap import average_precision, precision_recall
from synthaug.evaluate.results import ProtocolResult

S = Path("results/synthetic")
REAL = "adaboost_100_seeds.json"
# cell tag -> (folder pattern, seeds); the real-only cell of each seed is read from where it was stored
CELLS = {
    "HOG critic (float)": ("adaboost_critic/test_c{s}", (0, 1, 2)),
    "WL critic (float)": ("adaboost_wl_critic/test_w{s}", (0, 1, 2)),
    "WL critic, 8-bit": ("adaboost_wl_critic/test_q{s}", (0, 1, 2, 3)),
    "WL critic, 8-bit, seeds' poses": ("adaboost_wl_critic/test_p{s}", (0, 1, 2, 3, 4)),
}
REAL_AT = {0: "adaboost_critic/test_c0", 1: "adaboost_critic/test_c1", 2: "adaboost_critic/test_r2",
           3: "adaboost_critic/test_r3", 4: "adaboost_critic/test_r4"}


def added(folder: Path) -> Path:
    (f,) = [p for p in folder.glob("adaboost_100_seeds_*.json")]
    return f


def stats(r: ProtocolResult, seed: int, iou: float = 0.5) -> dict:
    pool = r.pools(iou)[seed]
    s, t, n = pool.pooled()
    p, rec, _ = precision_recall(s, t, n)
    out = {"ap": average_precision(p, rec), "ceiling": float(t.sum()) / n, "p": p, "r": rec}
    out["videos"] = {stem: pool.ap(np.eye(pool.n_videos, dtype=np.int64)[i]) for i, stem in enumerate(r.stems)}
    out["buckets"] = [r.pools(iou, b)[seed].ap() for b in range(len(r.protocol.size_buckets))]
    return out


def prec_to(st: dict, upto: float) -> float:
    """Mean precision over recall [0, upto] (the area under p(r) up to ``upto``, over ``upto``)."""
    r, p = st["r"], st["p"]
    grid = np.linspace(0, upto, 201)[1:]
    return float(np.mean([p[r >= g].max() if np.any(r >= g) else 0.0 for g in grid]))


def main() -> None:
    real = {s: ProtocolResult.load(S / REAL_AT[s] / REAL) for s in REAL_AT}
    rs = {s: stats(real[s], s) for s in real}
    n_gt = [real[0].pools(0.5, b)[0].n_positive.sum() for b in range(len(real[0].protocol.size_buckets))]
    keep = [b for b, n in enumerate(n_gt) if n > 0]  # a bucket without test objects has no AP
    names = [f"{b.low:g}-{'' if b.high is None else f'{b.high:g}'} px ({n_gt[i]} objects)"
             for i, b in enumerate(real[0].protocol.size_buckets) if i in keep]
    print("real only per seed: AP / recall ceiling:",
          ", ".join(f"{s}: {rs[s]['ap']:.3f} / {rs[s]['ceiling']:.3f}" for s in rs))
    per_video = defaultdict(list)
    print("\n| cell | seed | ΔAP@0.5 | Δ recall ceiling | Δ precision over the shared recall | " +
          " | ".join(f"Δ AP {n}" for n in names) + " |")
    print("|---" * (5 + len(names)) + "|")
    for tag, (pat, seeds) in CELLS.items():
        for s in seeds:
            c = ProtocolResult.load(added(S / pat.format(s=s)))
            assert c.stems == real[s].stems and s in c.seeds
            cs = stats(c, s)
            upto = min(cs["ceiling"], rs[s]["ceiling"])
            dp = prec_to(cs, upto) - prec_to(rs[s], upto)
            db = [cs["buckets"][b] - rs[s]["buckets"][b] for b in keep]
            print(f"| {tag} | {s} | {cs['ap'] - rs[s]['ap']:+.3f} | {cs['ceiling'] - rs[s]['ceiling']:+.3f} | "
                  f"{dp:+.3f} (to recall {upto:.2f}) | " + " | ".join(f"{x:+.3f}" for x in db) + " |")
            for stem, v in cs["videos"].items():
                per_video[stem].append(v - rs[s]["videos"][stem])
    print("\nper test video, every cell and seed above (n = %d): mean Δ AP, share of cells up, real-only AP "
          "(mean over seeds), objects and their median size; the cells of one seed share its real-only cell"
          % len(next(iter(per_video.values()))))
    n_obj = {v.stem: v.n_objects for v in real[0].seeds[0].videos}
    size = {v.stem: float(np.median(np.asarray(v.gt_size, float))) for v in real[0].seeds[0].videos}
    for stem, d in sorted(per_video.items(), key=lambda kv: np.mean(kv[1])):
        ra = np.mean([rs[s]["videos"][stem] for s in rs])
        print(f"  {stem}: {np.mean(d):+.3f}, {np.mean(np.array(d) > 0):.2f} up, real {ra:.3f}, {n_obj[stem]} objects, "
              f"median {size[stem]:.0f} px")


if __name__ == "__main__":
    main()
