"""Summaries of protocol results and the markdown table every experiment reports.

:func:`summarize` / :func:`summarize_conditions` compute every number of a condition
(:class:`ConditionSummary`: APs with video-bootstrap intervals, AP per size bucket, patch
AP / ROC-AUC, the paired difference to a baseline) and :func:`report_table` renders
``condition | seeds | AP@0.5 [95 % CI] | AP@0.3 [CI] | Δ vs baseline [CI]
| videos improved | Δ's CI with the seeds resampled too | AP per size bucket | patch AP / ROC-AUC``.

Example:
    >>> _f(0.12345), _f(float("nan")), _f(None, 1)
    ('0.123', '–', '–')
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import Interval, PairedDifference, bootstrap_seed_mean, paired_difference

__all__ = ["ConditionSummary", "summarize", "summarize_conditions", "report_table", "other_machine_note"]


@dataclass
class ConditionSummary:
    """The numbers of one row of :func:`report_table`.

    Attributes:
        condition, split, scale: as the result.
        seeds: seed ids with frame results (else with patch results); ``meets_min_seeds``: at least the protocol's minimum.
        n_videos: test videos (bootstrap units).
        ap: IoU -> mean-over-seeds pooled AP with its video-bootstrap interval.
        buckets: size-bucket label -> mean-over-seeds AP at the main IoU (NaN: no object in it).
        bucket_objects: size-bucket label -> labelled objects in it.
        paired: difference to the baseline at the main IoU (None for the baseline or incomparable results).
        paired_seeds: the same difference with the training seeds resampled as well as the videos
            (:func:`~synthaug.evaluate.stats.paired_difference` with ``resample_seeds``): training randomness counted.
        paired_note: why there is no paired difference, when there is none.
        other_machine_seeds: the paired seeds whose detectors the baseline's and this result's metadata say were
            trained on different machines (:meth:`~synthaug.evaluate.results.ProtocolResult.trained_elsewhere`):
            there the seed id pairs the seed set, not the training randomness; the table marks such a Δ with †.
        patch_ap, patch_auc: patch-classification AP and ROC-AUC with intervals (None without patches).
        n_patches: ``{"positive": n, "negative": n}``.
    """

    condition: str
    split: str
    scale: float
    seeds: list[int]
    meets_min_seeds: bool
    n_videos: int
    ap: dict[float, Interval]
    buckets: dict[str, float]
    bucket_objects: dict[str, int]
    paired: PairedDifference | None = None
    paired_note: str = ""
    paired_seeds: PairedDifference | None = None
    patch_ap: Interval | None = None
    patch_auc: Interval | None = None
    n_patches: dict[str, int] = field(default_factory=dict)
    other_machine_seeds: list[int] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {
            "condition": self.condition, "split": self.split, "scale": self.scale, "seeds": self.seeds,
            "meets_min_seeds": self.meets_min_seeds, "n_videos": self.n_videos,
            "ap": {f"{k:g}": v.to_json() for k, v in self.ap.items()},
            "buckets": {k: (None if math.isnan(v) else v) for k, v in self.buckets.items()},
            "bucket_objects": self.bucket_objects,
            "paired": None if self.paired is None else self.paired.to_json(), "paired_note": self.paired_note,
            "paired_seeds": None if self.paired_seeds is None else self.paired_seeds.to_json(),
            "patch_ap": None if self.patch_ap is None else self.patch_ap.to_json(),
            "patch_auc": None if self.patch_auc is None else self.patch_auc.to_json(),
            "n_patches": self.n_patches, "other_machine_seeds": self.other_machine_seeds,
        }


def summarize(result: ProtocolResult, baseline: ProtocolResult | None = None) -> ConditionSummary:
    """Every number of a condition: APs with CIs, per-bucket AP, patch metrics, and the paired
    difference to ``baseline`` (same protocol; same videos; seeds paired by id)."""
    p = result.protocol
    bs = p.bootstrap
    kw = dict(resamples=bs.resamples, seed=bs.seed, ci=bs.ci)
    ap: dict[float, Interval] = {}
    pools_main = result.pools(p.main_iou)
    if pools_main:
        for t in p.iou_thresholds:
            ap[t] = bootstrap_seed_mean(result.pools(t), **kw)
    buckets = {b.label: result.mean_ap(p.main_iou, b) for b in p.size_buckets}
    bucket_objects = {b.label: result.n_objects(b) for b in p.size_buckets}
    paired, paired_seeds, note, elsewhere = None, None, "", []
    if baseline is not None and baseline is not result:
        if baseline.protocol.fingerprint() != p.fingerprint():
            note = "other protocol"
        elif baseline.stems != result.stems or not pools_main:
            note = "other videos"
        else:
            base_pools = baseline.pools(p.main_iou)
            if not set(base_pools) & set(pools_main):
                note = "no common seed"
            else:
                paired = paired_difference(base_pools, pools_main, stems=result.stems, **kw)
                paired_seeds = paired_difference(base_pools, pools_main, stems=result.stems, resample_seeds=True, **kw)
                elsewhere = sorted(s for s in result.trained_elsewhere(baseline) if s in paired.seeds)
    patch_ap = patch_auc = None
    n_patches: dict[str, int] = {}
    pp = result.patch_pools()
    if pp:
        patch_ap = bootstrap_seed_mean(pp, metric="ap", **kw)
        patch_auc = bootstrap_seed_mean(pp, metric="roc_auc", **kw)
        first = result.seeds[next(iter(pp))].patches
        npos = int(sum(x.labels.sum() for x in first))
        n_patches = {"positive": npos, "negative": int(sum(x.labels.size for x in first)) - npos}
    return ConditionSummary(result.condition, result.split, result.scale, list(pools_main or pp), result.meets_min_seeds,
                            len(result.stems or result.patch_stems), ap, buckets, bucket_objects, paired, note,
                            paired_seeds, patch_ap, patch_auc, n_patches, elsewhere)


def summarize_conditions(results: Mapping[str, ProtocolResult], baseline: str | None = None) -> dict[str, ConditionSummary]:
    """:func:`summarize` for every condition (keys are the row labels), paired with ``results[baseline]``.

    Raises:
        ValueError: results measured with different protocols, or an unknown baseline.
    """
    if not results:
        raise ValueError("no result to summarize")
    fps = {r.protocol.fingerprint() for r in results.values()}
    if len(fps) != 1:
        raise ValueError(f"results were measured with different protocols ({sorted(fps)}): they cannot share a table")
    if baseline is not None and baseline not in results:
        raise ValueError(f"baseline {baseline!r} is not one of the conditions {list(results)}")
    base = results[baseline] if baseline is not None else None
    out = {}
    for name, r in results.items():
        s = summarize(r, None if name == baseline else base)
        s.condition = name
        out[name] = s
    return out


def _f(x: float | None, digits: int = 3) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}f}"


def other_machine_note(seeds: Mapping[str, Sequence[int]]) -> str:
    """The footnote of a table whose paired Δs are marked †: row label -> the seeds trained on another machine than
    the baseline's of the same id (:meth:`~synthaug.evaluate.results.ProtocolResult.trained_elsewhere`); ``""`` when no
    row has any.

    >>> other_machine_note({"a": [], "b": [1, 2]})[:60]
    "† seeds trained on another machine than the baseline's seeds"
    """
    apart = {name: list(v) for name, v in seeds.items() if v}
    if not apart:
        return ""
    return ("† seeds trained on another machine than the baseline's seeds of the same id ("
            + "; ".join(f"{n}: {', '.join(map(str, v))}" for n, v in apart.items()) + ", by each seed's "
            "`trained_on`): such pairs share the seed set but not the training randomness, which another instruction "
            "set changes in the last bits; retrain both sides on one machine to pair them.")


def report_table(results: Mapping[str, ProtocolResult], baseline: str | None = None, *, digits: int = 3,
                 summaries: Mapping[str, ConditionSummary] | None = None) -> str:
    """A markdown table of conditions measured with one protocol.

    Columns: condition | seeds | AP@<main IoU> [CI] | AP at the other IoUs [CI] | Δ AP vs
    ``baseline`` [CI] | videos improved | the Δ's CI with the training seeds resampled too | AP per size bucket
    | patch AP [CI] | patch ROC-AUC [CI]
    (patch columns only when some result has patches). A seed count below the protocol's
    minimum is marked ``⚠``. Below the table: the protocol, bootstrap settings, objects per bucket
    and how "videos improved" is counted.

    Args:
        results: row label -> result (all of one protocol).
        baseline: the row the paired differences are taken against (None: no Δ columns).
        digits: decimals.
        summaries: precomputed :func:`summarize_conditions` output (saves the bootstrap).
    """
    sums = dict(summaries) if summaries is not None else summarize_conditions(results, baseline)
    first = next(iter(results.values()))
    p = first.protocol
    others = [t for t in p.iou_thresholds[1:]]
    has_patch = any(s.patch_ap is not None for s in sums.values())
    ci_pct = f"{100 * p.bootstrap.ci:g} %"
    header = ["condition", "seeds", f"AP@{p.main_iou:g} [{ci_pct} CI]"] + [f"AP@{t:g} [CI]" for t in others]
    if baseline is not None:
        header += [f"Δ AP@{p.main_iou:g} vs {baseline} [CI]", "videos improved", "Δ CI, seeds resampled too"]
    header += [f"AP@{p.main_iou:g} {b.label}" for b in p.size_buckets]
    if has_patch:
        header += ["patch AP [CI]", "patch ROC-AUC [CI]"]
    rows = []
    for name, s in sums.items():
        label = name if results[name].scale == 1.0 else f"{name} (×{results[name].scale:g})"
        seeds = f"{len(s.seeds)}" + ("" if s.meets_min_seeds else " ⚠")
        row = [label, seeds] + [s.ap[t].format(digits) if t in s.ap else "–" for t in p.iou_thresholds]
        if baseline is not None:
            if name == baseline:
                row += ["(baseline)", "", ""]
            elif s.paired is None:
                row += [f"n/a ({s.paired_note})" if s.paired_note else "–", "–", "–"]
            else:
                d = s.paired.difference.format(digits, signed=True)
                if len(s.paired.seeds) != len(sums[baseline].seeds) or len(s.paired.seeds) != len(s.seeds):
                    d += f" (on {len(s.paired.seeds)} common seeds)"
                if s.other_machine_seeds:
                    d += " †"
                cs = s.paired_seeds.difference
                crossed = "–" if math.isnan(cs.low) else f"[{cs.low:+.{digits}f}, {cs.high:+.{digits}f}]"
                row += [d, s.paired.wins.format(), crossed]
        row += [_f(s.buckets[b.label], digits) for b in p.size_buckets]
        if has_patch:
            row += ["–" if s.patch_ap is None else s.patch_ap.format(digits),
                    "–" if s.patch_auc is None else s.patch_auc.format(digits)]
        rows.append(row)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    n_vid = max((s.n_videos for s in sums.values()), default=0)
    objs = next((s.bucket_objects for s in sums.values() if s.ap), {})
    n_frame_vid = any(s.ap for s in sums.values())
    lines += [
        "",
        f"Protocol `{p.name}` v{p.version} (fingerprint `{p.fingerprint()}`), split `{first.split}`: "
        f"every {p.split(first.split if first.split in ('test', 'val') else 'test').frame_stride}-th frame of {n_vid} videos. "
        f"AP = ∫ p(r) dr of all videos pooled, mean over training seeds; {ci_pct} percentile intervals from "
        f"{p.bootstrap.resamples} bootstrap resamples of the videos (seed {p.bootstrap.seed}, the same resamples for "
        f"every condition and seed). Δ: paired by seed id and resample.",
    ]
    if n_frame_vid:
        lines.append("Objects per size bucket (longest side of the labelled box): "
                     + ", ".join(f"{k}: {v}" for k, v in objs.items()) + ". In a bucket, objects of other sizes and "
                     "unmatched detections of other sizes are ignored (COCO).")
    if has_patch:
        npat = next((s.n_patches for s in sums.values() if s.n_patches), {})
        lines.append(f"Patches: {npat.get('positive', 0)} object crops (cropped like the seeds) and {npat.get('negative', 0)} "
                     f"background windows of the same frames and sizes; ROC-AUC counts ties as ½.")
    if baseline is not None:
        lines.append("Videos improved: videos whose own AP (mean over seeds) rose, out of the videos with a labelled "
                     "object (videos without one have no AP and are left out).")
        lines.append("Δ CI, seeds resampled too: the same resamples of the videos with the training seeds resampled "
                     "as well (pairs kept), so that the interval counts training randomness (another seed set, fit "
                     "or draw), which the video bootstrap holds fixed; coarse under 5 seeds.")
    note = other_machine_note({n: s.other_machine_seeds for n, s in sums.items()})
    if note:
        lines.append(note)
    if any(not s.meets_min_seeds for s in sums.values()):
        lines.append(f"⚠ fewer than the protocol's {p.min_training_seeds} training seeds.")
    return "\n".join(lines) + "\n"
