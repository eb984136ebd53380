"""The paper's experiments: the three detector families on real / perturbed / synthetic positives, scored on videos.

This module reproduces the paper's experiments (Rozantsev et al. 2015, Sec. 5)
on any videos in the shared format (``videos/*.mp4`` + ``labels/*.json``, one
box or null per frame) with a committed video split:

- :func:`baselines` — each detector trained on real seed patches only (100 and
  12 seeds) and on all labelled frames of the training videos (issue 4);
- :func:`table1_perturbation` — real only vs perturbed real vs ours (Table 1);
- :func:`fig9_effects_off` — each capture effect switched off in turn (Fig. 9);
- :func:`fig10_fitted_vs_uniform` — fitted Θ vs Θ uniform in [min, max] (Fig. 10);
- :func:`fig11_ratio` — synthetic images per real one (Fig. 11); the ratio is
  chosen on the *validation* videos and used by the other experiments;
- :func:`fig12_seeds` — number of seeds (Fig. 12);
- :func:`table2_detector_distance` — each detector with each distance (Table 2).

Every experiment is a set of *cells* (detector x training set x evaluation
split) run and cached by :class:`~synthaug.evaluate.context.ExperimentContext`,
so re-running an experiment (or another experiment that shares a cell, e.g.
"real only, 100 seeds") reuses it instead of training again: an interrupted
run resumes. Every experiment writes a markdown table (``<name>.md``), a plot
(``<name>.png``) and its numbers (``<name>.json``) into the output folder
(:mod:`synthaug.evaluate.reporting`), and returns the numbers.

The pieces live by concept; their names stay importable from here:

- detector training and the training sets: :mod:`synthaug.detectors.training`, :mod:`synthaug.detectors.training_sets`;
- evaluation sets, detection on them and AP: :mod:`synthaug.evaluate.videos`;
- the perturbation baseline: :mod:`synthaug.effects.perturb`;
- the runner and its cell cache: :mod:`synthaug.evaluate.context`;
- tables and plots: :mod:`synthaug.evaluate.reporting`.

Example:
    >>> EXPERIMENTS["fig11_ratio"] is fig11_ratio, list(EXPERIMENTS)[:2]
    (True, ['baselines', 'fig11_ratio'])
"""

from __future__ import annotations

import json
import time
from typing import Any, Callable, Mapping, Sequence

import torch

from synthaug._io import atomic_write_text

# Names that moved to their own modules stay importable from here (backwards compatibility).
from synthaug.detectors.training import DETECTORS, DetectorKind, TrainOptions, train_detector  # noqa: F401
from synthaug.detectors.training_sets import (  # noqa: F401
    frames_training_set,
    mining_frames,
    negative_pool,
    perturbed_positives,
    real_positives,
    synthetic_positives,
)
from synthaug.evaluate.context import ExperimentContext
from synthaug.effects.perturb import perturb_patches  # noqa: F401
from synthaug.evaluate.reporting import _ap, _fmt, _plot, _stem, _write_report  # noqa: F401
from synthaug.evaluate.videos import EvalResult, EvalSet, detect_on_eval_set, evaluate_on_videos, load_eval_set  # noqa: F401
from synthaug.params import CaptureParams

__all__ = [
    "DETECTORS",
    "PAPER_DISTANCE",
    "EXPERIMENTS",
    "TrainOptions",
    "EvalSet",
    "EvalResult",
    "ExperimentContext",
    "train_detector",
    "load_eval_set",
    "detect_on_eval_set",
    "evaluate_on_videos",
    "perturb_patches",
    "real_positives",
    "perturbed_positives",
    "synthetic_positives",
    "frames_training_set",
    "chosen_ratios",
    "baselines",
    "table1_perturbation",
    "fig9_effects_off",
    "fig10_fitted_vs_uniform",
    "fig11_ratio",
    "fig12_seeds",
    "table2_detector_distance",
]

PAPER_DISTANCE: dict[str, str] = {"hog": "hog", "adaboost": "wl_learned", "cnn": "cnn"}
"""The distance the paper pairs with each detector (d_HOG, d_WL^L, d_CNN)."""
DISTANCES: tuple[str, ...] = ("eucl", "hog", "wl_random", "wl_learned", "cnn")


# --------------------------------------------------------------------------- experiments
def baselines(ctx: ExperimentContext, *, detectors: Sequence[str] = DETECTORS, seed_counts: Sequence[int] = (100, 12),
              all_frames: bool = True, frame_step: int = 1) -> dict[str, Any]:
    """Issue 4 item 4: each detector on real seed patches only and on all labelled training frames.

    Writes ``baselines.md/.json/.png``. Returns ``{detector: {setting: cell}}``.
    """
    numbers: dict[str, Any] = {}
    frames_data: dict[str, Any] = {}

    def frames_build() -> dict[str, Any]:
        if not frames_data:
            t0 = time.perf_counter()
            d = frames_training_set(ctx.videos("train"), ctx.videos_dir, ctx.labels_dir, frame_step=frame_step, seed=ctx.seed)
            d["negatives"] = torch.cat([ctx.negatives(max(seed_counts)), d["negatives"]])
            d["box_in_window"] = ctx.box_in_window(d.pop("boxes"))
            frames_data.update(d)
            ctx.log(f"all-frames training set: {d['positives'].shape[0]} positives, {d['negatives'].shape[0]} negatives "
                    f"({time.perf_counter() - t0:.0f}s)")
        return frames_data

    settings = [(f"real {n} seeds", f"real_{n}", ctx.real_build(n)) for n in seed_counts]
    if all_frames:
        settings.append((f"all train frames (step {frame_step})", f"frames_step{frame_step}", frames_build))
    for det in detectors:
        numbers[det] = {}
        for label, key, build in settings:
            numbers[det][label] = ctx.cell(key, det, build)
    header = ["detector"] + [s[0] for s in settings]
    rows = [[d] + [_ap(numbers[d][s[0]]) for s in settings] for d in detectors]
    rows03 = [[d + " (AP@IoU0.3)"] + [_ap(numbers[d][s[0]], key="ap_iou03") for s in settings] for d in detectors]
    pos = ["#positives"] + [numbers[detectors[0]][s[0]]["train"].get("positives") for s in settings]
    _write_report(ctx, "baselines", f"{ctx.class_name}: AP on the test videos (IoU 0.5), real training data only",
                  header, rows + rows03 + [pos], numbers)
    _plot(ctx.out_dir / f"{_stem(ctx, 'baselines')}.png", "bar", {d: {s[0]: _ap(numbers[d][s[0]]) for s in settings} for d in detectors},
          title=f"{ctx.class_name}: real-data baselines (test AP)", xlabel="detector")
    return numbers


def fig11_ratio(ctx: ExperimentContext, *, detectors: Sequence[str] = DETECTORS, ratios: Sequence[float] = (0, 5, 10, 20, 50, 100, 200),
                n_seeds: int = 100) -> dict[str, Any]:
    """Fig. 11: synthetic images per real one. Chooses the ratio per detector on the validation videos.

    Returns ``{"chosen": {detector: ratio}, "val": {...}, "test": {...}}``; the
    choice is also saved in ``chosen_ratio.json`` for the other experiments.
    """
    val: dict[str, dict[float, float | None]] = {}
    test: dict[str, dict[float, float | None]] = {}
    chosen: dict[str, float] = {}
    for det in detectors:
        val[det], test[det] = {}, {}
        dist = PAPER_DISTANCE[det]
        for r in ratios:
            if r == 0:
                c = ctx.cell(f"real_{n_seeds}", det, ctx.real_build(n_seeds), splits=("val", "test"))
            else:
                c = ctx.cell(f"syn_{n_seeds}_{dist}_r{r:g}", det, ctx.synthetic_build(n_seeds, r, dist), splits=("val", "test"))
            val[det][r], test[det][r] = _ap(c, "val"), _ap(c, "test")
        scored = [r for r in ratios if val[det][r] is not None]
        if scored:  # best validation AP; ties go to the smaller ratio
            chosen[det] = max(scored, key=lambda r: (val[det][r], -r))
    numbers = {"chosen": chosen, "val": val, "test": test, "n_seeds": n_seeds}
    path = ctx.out_dir / "chosen_ratio.json"
    ctx.out_dir.mkdir(parents=True, exist_ok=True)
    merged = (json.loads(path.read_text()) if path.is_file() else {}) | chosen
    atomic_write_text(path, json.dumps(merged, indent=1, sort_keys=True) + "\n")
    header = ["detector (distance)"] + [f"r={r:g}" for r in ratios] + ["chosen on val"]
    rows = []
    for det in detectors:
        rows.append([f"{det} ({PAPER_DISTANCE[det]}) val"] + [val[det][r] for r in ratios] + [f"{chosen[det]:g}" if det in chosen else "–"])
        rows.append([f"{det} ({PAPER_DISTANCE[det]}) test"] + [test[det][r] for r in ratios] + [""])
    _write_report(ctx, "fig11_ratio", f"{ctx.class_name}: AP vs synthetic images per real one ({n_seeds} seeds)", header, rows, numbers)
    series = {f"{d} test": test[d] for d in detectors} | {f"{d} val": val[d] for d in detectors}
    _plot(ctx.out_dir / f"{_stem(ctx, 'fig11_ratio')}.png", "line", series, title=f"{ctx.class_name}: synthetic per real (★ = chosen on val)",
          xlabel="synthetic per real", logx=True, marks={f"{d} val": chosen[d] for d in detectors if d in chosen})
    return numbers


class _ChosenRatios(dict):
    def __init__(self, got: Mapping[str, float], strict: bool) -> None:
        super().__init__({k: float(v) for k, v in got.items()})
        self.strict = strict

    def __missing__(self, det: str) -> float:
        if self.strict:
            raise ValueError(f"no synthetic-to-real ratio chosen on validation for detector {det!r}: run fig11_ratio for it first")
        return float("nan")


def chosen_ratios(ctx: ExperimentContext) -> dict[str, float]:
    """Ratios chosen on the validation videos by :func:`fig11_ratio`.

    A detector without a choice raises ValueError (never a test-chosen or
    default ratio), except with ``ctx.cached_only`` where it maps to NaN
    (its cells are then reported missing).
    """
    path = ctx.out_dir / "chosen_ratio.json"
    got = json.loads(path.read_text()) if path.is_file() else {}
    return _ChosenRatios(got, strict=not ctx.cached_only)


def table1_perturbation(ctx: ExperimentContext, *, detectors: Sequence[str] = DETECTORS, n_seeds: int = 100,
                        ratios: Mapping[str, float] | None = None) -> dict[str, Any]:
    """Table 1: real only vs perturbed real images vs ours, at the validation-chosen ratio."""
    chosen = chosen_ratios(ctx)
    ratios = {d: (ratios[d] if ratios and d in ratios else chosen[d]) for d in detectors}
    numbers: dict[str, Any] = {}
    for det in detectors:
        r = ratios[det]
        dist = PAPER_DISTANCE[det]
        numbers[det] = {
            "ratio": r,
            "real only": ctx.cell(f"real_{n_seeds}", det, ctx.real_build(n_seeds)),
            "perturbed": ctx.cell(f"perturbed_{n_seeds}_r{r:g}", det, ctx.perturbed_build(n_seeds, r)),
            "ours": ctx.cell(f"syn_{n_seeds}_{dist}_r{r:g}", det, ctx.synthetic_build(n_seeds, r, dist)),
        }
    cols = ["real only", "perturbed", "ours"]
    rows = [[f"{d} ({PAPER_DISTANCE[d]}, r={numbers[d]['ratio']:g})"] + [_ap(numbers[d][c]) for c in cols] for d in detectors]
    rows += [[f"{d} AP@IoU0.3"] + [_ap(numbers[d][c], key="ap_iou03") for c in cols] for d in detectors]
    _write_report(ctx, "table1_perturbation", f"{ctx.class_name}: real only vs perturbing the real images vs ours (test AP, {n_seeds} seeds)",
                  ["detector"] + cols, rows, numbers)
    _plot(ctx.out_dir / f"{_stem(ctx, 'table1_perturbation')}.png", "bar", {d: {c: _ap(numbers[d][c]) for c in cols} for d in detectors},
          title=f"{ctx.class_name}: Table 1", xlabel="detector")
    return numbers


EFFECT_ABBREV = {"boundary_blur": "BB", "motion_blur": "MB", "object_noise": "RN", "material": "MP"}


def _paper_effects() -> list[str]:
    return list(CaptureParams.sample(1, generator=torch.Generator().manual_seed(0)).effects)


def fig9_effects_off(ctx: ExperimentContext, *, detectors: Sequence[str] = ("cnn",), n_seeds: int = 100,
                     refit: bool = False) -> dict[str, Any]:
    """Fig. 9: each capture effect switched off in turn.

    With ``refit=True`` Θ is re-fitted without the effect (the paper); by
    default the full fit is reused and the effect is simply not applied at
    generation (cheaper; the other parameters then keep the values fitted
    with the effect on).
    """
    effects = _paper_effects()
    ratios = chosen_ratios(ctx)
    numbers: dict[str, Any] = {"effects": effects, "refit": refit}
    for det in detectors:
        dist, r = PAPER_DISTANCE[det], ratios[det]
        row = {"all": ctx.cell(f"syn_{n_seeds}_{dist}_r{r:g}", det, ctx.synthetic_build(n_seeds, r, dist))}
        for e in effects:
            keep = [x for x in effects if x != e]
            if refit:
                b = ctx.synthetic_build(n_seeds, r, dist, fit_effects=keep, fit_tag=f"no_{e}")
                key = f"syn_{n_seeds}_{dist}_r{r:g}_refit_no_{e}"
            else:
                b = ctx.synthetic_build(n_seeds, r, dist, effects=keep)
                key = f"syn_{n_seeds}_{dist}_r{r:g}_no_{e}"
            row[f"no {EFFECT_ABBREV.get(e, e)}"] = ctx.cell(key, det, b)
        row["real only"] = ctx.cell(f"real_{n_seeds}", det, ctx.real_build(n_seeds))
        numbers[det] = row
    cols = ["all"] + [f"no {EFFECT_ABBREV.get(e, e)}" for e in effects] + ["real only"]
    rows = [[f"{d} ({PAPER_DISTANCE[d]}, r={ratios[d]:g})"] + [_ap(numbers[d][c]) for c in cols] for d in detectors]
    _write_report(ctx, "fig9_effects_off", f"{ctx.class_name}: each effect switched off (test AP, {n_seeds} seeds)",
                  ["detector"] + cols, rows, numbers)
    _plot(ctx.out_dir / f"{_stem(ctx, 'fig9_effects_off')}.png", "bar", {d: {c: _ap(numbers[d][c]) for c in cols} for d in detectors},
          title=f"{ctx.class_name}: Fig. 9 (effects off)", xlabel="detector")
    return numbers


def fig10_fitted_vs_uniform(ctx: ExperimentContext, *, detectors: Sequence[str] = DETECTORS, n_seeds: int = 100) -> dict[str, Any]:
    """Fig. 10: fitted Θ vs Θ drawn uniformly between the min and max of the fitted values."""
    ratios = chosen_ratios(ctx)
    numbers: dict[str, Any] = {}
    for det in detectors:
        dist, r = PAPER_DISTANCE[det], ratios[det]
        numbers[det] = {
            "real only": ctx.cell(f"real_{n_seeds}", det, ctx.real_build(n_seeds)),
            "uniform Θ": ctx.cell(f"syn_{n_seeds}_{dist}_r{r:g}_uniform", det, ctx.synthetic_build(n_seeds, r, dist, capture_sampling="uniform")),
            "fitted Θ": ctx.cell(f"syn_{n_seeds}_{dist}_r{r:g}", det, ctx.synthetic_build(n_seeds, r, dist)),
        }
    cols = ["real only", "uniform Θ", "fitted Θ"]
    rows = [[f"{d} ({PAPER_DISTANCE[d]}, r={ratios[d]:g})"] + [_ap(numbers[d][c]) for c in cols] for d in detectors]
    _write_report(ctx, "fig10_fitted_vs_uniform", f"{ctx.class_name}: fitted vs uniform capture parameters (test AP)",
                  ["detector"] + cols, rows, numbers)
    _plot(ctx.out_dir / f"{_stem(ctx, 'fig10_fitted_vs_uniform')}.png", "bar", {d: {c: _ap(numbers[d][c]) for c in cols} for d in detectors},
          title=f"{ctx.class_name}: Fig. 10", xlabel="detector")
    return numbers


def fig12_seeds(ctx: ExperimentContext, *, detectors: Sequence[str] = ("cnn",), seed_counts: Sequence[int] = (12, 25, 50, 100)) -> dict[str, Any]:
    """Fig. 12: number of seeds (each seed set fitted with the detector's distance), real only vs ours."""
    ratios = chosen_ratios(ctx)
    numbers: dict[str, Any] = {}
    for det in detectors:
        dist, r = PAPER_DISTANCE[det], ratios[det]
        numbers[det] = {"real only": {}, "ours": {}}
        for n in seed_counts:
            numbers[det]["real only"][n] = ctx.cell(f"real_{n}", det, ctx.real_build(n))
            numbers[det]["ours"][n] = ctx.cell(f"syn_{n}_{dist}_r{r:g}", det, ctx.synthetic_build(n, r, dist))
    header = ["detector", "setting"] + [f"{n} seeds" for n in seed_counts]
    rows = []
    for d in detectors:
        for s in ("real only", "ours"):
            rows.append([f"{d} ({PAPER_DISTANCE[d]}, r={ratios[d]:g})", s] + [_ap(numbers[d][s][n]) for n in seed_counts])
    _write_report(ctx, "fig12_seeds", f"{ctx.class_name}: AP vs number of seeds (test AP)", header, rows, numbers)
    _plot(ctx.out_dir / f"{_stem(ctx, 'fig12_seeds')}.png", "line", {f"{d} {s}": {n: _ap(numbers[d][s][n]) for n in seed_counts} for d in detectors for s in ("real only", "ours")},
          title=f"{ctx.class_name}: Fig. 12", xlabel="number of seeds")
    return numbers


def table2_detector_distance(ctx: ExperimentContext, *, detectors: Sequence[str] = DETECTORS, distances: Sequence[str] = DISTANCES,
                             n_seeds: int = 100) -> dict[str, Any]:
    """Table 2: each detector trained with synthetic images fitted with each distance (ratio chosen on val for the paper's distance)."""
    ratios = chosen_ratios(ctx)
    numbers: dict[str, Any] = {}
    for det in detectors:
        r = ratios[det]
        numbers[det] = {"real only": ctx.cell(f"real_{n_seeds}", det, ctx.real_build(n_seeds))}
        for dist in distances:
            numbers[det][dist] = ctx.cell(f"syn_{n_seeds}_{dist}_r{r:g}", det, ctx.synthetic_build(n_seeds, r, dist))
    cols = ["real only"] + list(distances)
    rows = [[f"{d} (r={ratios[d]:g})"] + [_ap(numbers[d][c]) for c in cols] for d in detectors]
    _write_report(ctx, "table2_detector_distance", f"{ctx.class_name}: detector x distance (test AP, {n_seeds} seeds)",
                  ["detector"] + cols, rows, numbers)
    _plot(ctx.out_dir / f"{_stem(ctx, 'table2_detector_distance')}.png", "bar", {d: {c: _ap(numbers[d][c]) for c in cols} for d in detectors},
          title=f"{ctx.class_name}: Table 2", xlabel="detector")
    return numbers


EXPERIMENTS: dict[str, Callable[..., dict[str, Any]]] = {
    "baselines": baselines,
    "fig11_ratio": fig11_ratio,
    "table1_perturbation": table1_perturbation,
    "fig10_fitted_vs_uniform": fig10_fitted_vs_uniform,
    "fig9_effects_off": fig9_effects_off,
    "fig12_seeds": fig12_seeds,
    "table2_detector_distance": table2_detector_distance,
}
"""Experiments by name, in the order ``all`` runs them (fig11 first: it chooses the ratios)."""
