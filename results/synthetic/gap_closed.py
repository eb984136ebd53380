"""Issue 16's 12-seed target from stored protocol results: how much of the AP gap between few and many real seeds
the added positives close (trains nothing).

    PYTHONPATH=. python results/synthetic/gap_closed.py --few A.json --added B.json [--added D.json ...] --many C.json \
        [--title T] [--out MD]

Each argument may list files of one condition separated by commas (e.g. one run per training seed).
``--few``: real seeds only (e.g. 12); ``--added``: the same seeds + added positives; ``--many``: more real seeds
(e.g. 100), all with the same protocol, test videos and training seeds. Printed: AP@main IoU per condition with its
95 % CI and per seed, the paired tables against ``--few`` and ``--many`` (the runner's ``report_table``), and per
added condition the closed share (AP(added) − AP(few)) / (AP(many) − AP(few)) with its percentile interval over the
protocol's video resamples (the same resamples for every condition), and the linear statistic behind "closes ≥ 50 %":
AP(added) − (AP(few) + AP(many)) / 2 (≥ 0 exactly when the share is ≥ 0.5 and the gap > 0); when every condition
holds the same training seeds, the same again with the seeds resampled too (training randomness counted).
"""
from __future__ import annotations

import argparse
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import bootstrap_seed_mean, percentile_interval
from synthaug.evaluate.summary import report_table


def fmt(x: float, signed: bool = False) -> str:
    return "nan" if not np.isfinite(x) else (f"{x:+.3f}" if signed else f"{x:.3f}")


def resampled(res: Mapping[str, ProtocolResult], resample_seeds: bool = False
              ) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """Per condition: the mean-over-seeds AP@main IoU on each of the protocol's video resamples, and on the videos.

    With ``resample_seeds`` the training seeds are resampled too (one draw of seed ids for every condition, so a drawn
    id brings all its conditions): every condition must hold the same seeds.
    """
    first = next(iter(res.values()))
    p, stems = first.protocol, first.stems
    for k, r in res.items():
        assert r.stems == stems, f"{k}: other videos"
        assert r.protocol.fingerprint() == p.fingerprint(), f"{k}: other protocol"
    pools = {k: r.pools(p.main_iou) for k, r in res.items()}
    if resample_seeds:  # the same seed ids in the same order, so that one draw picks the same seeds everywhere
        seeds = sorted(pools[next(iter(pools))])
        assert all(sorted(v) == seeds for v in pools.values()), "conditions hold other seeds"
        pools = {k: {s: v[s] for s in seeds} for k, v in pools.items()}
    kw = dict(resamples=p.bootstrap.resamples, seed=p.bootstrap.seed, ci=p.bootstrap.ci, resample_seeds=resample_seeds)
    return ({k: bootstrap_seed_mean(v, **kw).samples for k, v in pools.items()},
            {k: r.mean_ap(p.main_iou) for k, r in res.items()})


def gap_lines(samples: Mapping[str, np.ndarray], est: Mapping[str, float], few: str, many: str,
              added: list[str], labels: Mapping[str, str], ci: float,
              resamples: str = "the same video resamples") -> list[str]:
    """The closed share and the midpoint statistic of each ``added`` condition, as markdown bullets."""
    sa, sc = samples[few], samples[many]
    gap = sc - sa
    glo, ghi = percentile_interval(gap, ci)
    lines = []
    for cond in added:
        sx = samples[cond]
        share = np.where(gap > 0, (sx - sa) / np.where(gap > 0, gap, 1.0), np.nan)
        share_est = (est[cond] - est[few]) / (est[many] - est[few])
        slo, shi = percentile_interval(share, ci)
        mid = sx - (sa + sc) / 2.0
        mlo, mhi = percentile_interval(mid, ci)
        mid_est = est[cond] - (est[few] + est[many]) / 2.0
        lines += [
            f"- {labels[cond]}: gap AP(100) - AP(12) = {fmt(est[many] - est[few], True)} [{fmt(glo, True)}, {fmt(ghi, True)}] "
            f"({int(np.sum(gap <= 0))} of {len(gap)} resamples with no positive gap, left out of the share's interval)",
            f"  - closed share (AP(x) - AP(12)) / (AP(100) - AP(12)) = **{share_est:.2f}** [{slo:.2f}, {shi:.2f}] "
            f"(percentile interval over {resamples}; "
            f"P(share >= 0.5) = {np.mean(share[~np.isnan(share)] >= 0.5):.2f} of the "
            f"resamples with a positive gap)",
            f"  - AP(x) - (AP(12) + AP(100)) / 2 = {fmt(mid_est, True)} [{fmt(mlo, True)}, {fmt(mhi, True)}] "
            f"(>= 0 <=> the target's 50 % is met)",
        ]
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--few", required=True)
    ap.add_argument("--added", nargs="+", required=True)
    ap.add_argument("--many", required=True)
    ap.add_argument("--title", default="Added positives against few and many real seeds")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    files = {"few": a.few, **{f"added{i}": f for i, f in enumerate(a.added)}, "many": a.many}
    res = {k: ProtocolResult.combine([ProtocolResult.load(x) for x in f.split(",")]) for k, f in files.items()}
    labels = {k: r.condition for k, r in res.items()}
    assert len(set(labels.values())) == len(labels), f"two files hold one condition: {labels}"
    p = res["few"].protocol
    samples, est = resampled(res)
    lines = [f"# {a.title}", "", f"Protocol `{p.name}` (fingerprint `{p.fingerprint()}`), split `{res['few'].split}`.", "",
             "| condition | AP@0.5 [95 % CI] | per seed |", "|---|---|---|"]
    for k, r in res.items():
        lo, hi = percentile_interval(samples[k], p.bootstrap.ci)
        per = " / ".join(fmt(x) for _, x in sorted(r.per_seed_ap(p.main_iou).items()))
        lines.append(f"| {labels[k]} | {fmt(est[k])} [{fmt(lo)}, {fmt(hi)}] | {per} |")
    by_label = {labels[k]: r for k, r in res.items()}
    lines += ["", f"## Paired against {labels['few']}", "", report_table(by_label, baseline=labels["few"]), "",
              f"## Paired against {labels['many']}", "", report_table(by_label, baseline=labels["many"]), "",
              "## Gap closed", ""]
    added = [k for k in res if k.startswith("added")]
    lines += gap_lines(samples, est, "few", "many", added, labels, p.bootstrap.ci)
    if len({tuple(sorted(r.seed_ids)) for r in res.values()}) == 1 and len(res["few"].seed_ids) > 1:
        lines += ["", "## Gap closed, the training seeds resampled too", "",
                  "The same statistics with the training seeds resampled as well as the videos (one draw of seed ids "
                  "for every condition; `resample_seed_counts`): training randomness counted; coarse under 5 "
                  "seeds.", ""]
        lines += gap_lines(resampled(res, resample_seeds=True)[0], est, "few", "many", added, labels, p.bootstrap.ci,
                           "the same resamples of videos and training seeds")
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        Path(a.out).write_text(text)


if __name__ == "__main__":
    main()
