"""Experiment runner: train the three detector families on real / perturbed / synthetic positives, score them on videos.

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
split). A cell's result is stored in ``<out>/cells.json`` under a key naming
everything it depends on, so re-running an experiment (or another experiment
that shares a cell, e.g. "real only, 100 seeds") reuses it instead of
training again: an interrupted run resumes. Every experiment writes a
markdown table (``<name>.md``), a plot (``<name>.png``) and its numbers
(``<name>.json``) into the output folder, and returns the numbers.

Randomness: every draw comes from a generator seeded by the context's ``seed``
(and a per-cell offset), so a cell is deterministic given its key.

Example:
    >>> import torch
    >>> x = torch.rand(4, 1, 40, 40, generator=torch.Generator().manual_seed(0))
    >>> y = perturb_patches(x, 3, generator=torch.Generator().manual_seed(1))
    >>> tuple(y.shape), bool(((y >= 0) & (y <= 1)).all())
    ((12, 1, 40, 40), True)
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Literal, Mapping, Sequence

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor

# Detector training lives beside the detectors (synthaug.detectors.training); these names stay importable from here.
from synthaug.detectors.training import (  # noqa: F401
    DETECTORS,
    DetectorKind,
    TrainOptions,
    _check_kind,
    frames_training_set,
    mining_frames,
    negative_pool,
    real_positives,
    synthetic_positives,
    train_detector,
)
# Evaluation on labelled videos lives in synthaug.evaluate.videos; these names stay importable from here.
from synthaug.evaluate.videos import EvalResult, EvalSet, detect_on_eval_set, evaluate_on_videos, load_eval_set  # noqa: F401

__all__ = [
    "DETECTORS",
    "PAPER_DISTANCE",
    "TrainOptions",
    "EvalSet",
    "EvalResult",
    "ExperimentContext",
    "train_detector",
    "load_eval_set",
    "evaluate_on_videos",
    "perturb_patches",
    "real_positives",
    "perturbed_positives",
    "synthetic_positives",
    "frames_training_set",
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


# --------------------------------------------------------------------------- positive sets
def perturb_patches(
    patches: Tensor,
    copies: int,
    *,
    generator: torch.Generator,
    max_rotation_deg: float = 15.0,
    max_translation: float = 0.08,
    mirror: bool = True,
    max_blur_sigma: float = 1.5,
    max_noise_sigma: float = 0.03,
) -> Tensor:
    """The classic augmentation baseline: random rotation, translation, mirroring, blur and noise.

    Every output is one input patch warped by a random rotation (uniform in
    ±``max_rotation_deg``) and translation (uniform in ±``max_translation`` of
    the side, border pixels replicated), mirrored with probability 1/2,
    blurred by a Gaussian of σ uniform in [0, ``max_blur_sigma``] px and given
    Gaussian noise of σ uniform in [0, ``max_noise_sigma``], then clipped to [0, 1].
    The input is not modified.

    Args:
        patches: float patches in [0, 1].
        copies: perturbed copies per patch (>= 0).
        generator: the only source of randomness.
        max_rotation_deg, max_translation, mirror, max_blur_sigma, max_noise_sigma: ranges.

    Returns:
        ``copies * N`` perturbed patches; copy ``c`` of patch ``i`` is row ``c * N + i``.

    Shape:
        - patches: (N, 1, P, P)
        - output: (copies * N, 1, P, P)
    """
    if not isinstance(patches, Tensor) or patches.dim() != 4 or not patches.dtype.is_floating_point:
        raise ValueError(f"patches must be a float (N, C, P, P) tensor, got {getattr(patches, 'shape', patches)}")
    if copies < 0:
        raise ValueError(f"copies must be >= 0, got {copies}")
    n, c, h, w = patches.shape
    m = n * copies
    if m == 0:
        return patches.new_zeros(0, c, h, w)
    x = patches.repeat(copies, 1, 1, 1)
    angle = (torch.rand(m, generator=generator) * 2 - 1) * math.radians(max_rotation_deg)
    shift = (torch.rand(m, 2, generator=generator) * 2 - 1) * (2 * max_translation)  # normalised coords span 2
    flip = (torch.rand(m, generator=generator) < 0.5) if mirror else torch.zeros(m, dtype=torch.bool)
    sigma = torch.rand(m, generator=generator) * max_blur_sigma
    noise_sigma = torch.rand(m, generator=generator) * max_noise_sigma
    noise = torch.randn(m, c, h, w, generator=generator)
    cos, sin = torch.cos(angle), torch.sin(angle)
    sx = torch.where(flip, -1.0, 1.0)
    theta = torch.stack([torch.stack([cos * sx, -sin, shift[:, 0]], 1), torch.stack([sin * sx, cos, shift[:, 1]], 1)], 1)
    grid = F.affine_grid(theta.to(x.dtype), list(x.shape), align_corners=False)
    x = F.grid_sample(x, grid, mode="bilinear", padding_mode="border", align_corners=False)
    # per-sample separable Gaussian blur (σ = 0 -> identity kernel)
    radius = max(1, math.ceil(3 * max_blur_sigma))
    t = torch.arange(-radius, radius + 1, dtype=x.dtype)
    k = torch.exp(-0.5 * (t[None] / sigma.clamp_min(1e-3)[:, None].to(x.dtype)) ** 2)
    k = k / k.sum(1, keepdim=True)  # (m, 2r+1)
    xb = x.reshape(1, m * c, h, w)
    kc = k.repeat_interleave(c, 0)
    xb = F.conv2d(F.pad(xb, (radius, radius, 0, 0), mode="replicate"), kc[:, None, None, :], groups=m * c)
    xb = F.conv2d(F.pad(xb, (0, 0, radius, radius), mode="replicate"), kc[:, None, :, None], groups=m * c)
    x = xb.reshape(m, c, h, w) + noise * noise_sigma[:, None, None, None].to(x.dtype)
    return x.clamp(0.0, 1.0)


def perturbed_positives(seedset: Any, copies: int, *, seed: int = 0) -> Tensor:
    """Real patches plus ``copies`` perturbed versions of each (the Table 1 baseline)."""
    real = real_positives(seedset)
    return torch.cat([real, perturb_patches(real, copies, generator=torch.Generator().manual_seed(seed))])


# --------------------------------------------------------------------------- context and cells
@dataclass
class ExperimentContext:
    """Everything an experiment needs: data locations, budgets, and the cell cache.

    Args:
        out_dir: results folder (``cells.json``, tables, plots).
        class_name: ``"drone"`` or ``"airplane"`` (selects videos and seed sets).
        seedsets_dir: folder holding ``<class>_<n>`` seed sets.
        mesh: mesh of the class.
        fits_dir: folder of capture-parameter fits ``<class>_<n>_<distance>[_<tag>].json``
            (made with :func:`synthaug.fit.fitting.fit_seedset` when missing).
        videos_dir, labels_dir: the shared-format folders.
        split_file: the committed video split.
        stride_k: score every k-th test frame.
        val_stride_k: every k-th validation frame (model selection).
        max_test_videos, max_val_videos: caps on the number of videos (None: all).
        scales: sliding-window pyramid (None: the default).
        options: training budgets.
        seed: base seed of every cell.
        fit_workers: processes for fits made on the fly.
        fit_budget: objective evaluations per seed for fits made on the fly.
        log: progress printer.
        cells_path: the cell cache (default ``<out_dir>/cells.json``); several
            results folders may share one so that common cells run once.
        cached_only: never train: cells missing from the cache are reported
            as missing ("–"); regenerates every table from the cache.
    """

    out_dir: Path
    class_name: str = "drone"
    seedsets_dir: Path = Path("data/halmstad/seedsets")
    mesh: str = "../shared/data/meshes/quadcopter.glb"
    fits_dir: Path | None = None
    videos_dir: Path = Path("../shared/data/halmstad/videos")
    labels_dir: Path = Path("../shared/data/halmstad/labels")
    split_file: Path = Path("configs/splits/halmstad.json")
    stride_k: int = 10
    val_stride_k: int = 20
    max_test_videos: int | None = None
    max_val_videos: int | None = None
    scales: tuple[float, ...] | None = None
    options: TrainOptions = field(default_factory=TrainOptions)
    seed: int = 0
    fit_workers: int = 2
    fit_budget: int = 1500
    log: Callable[[str], None] = print
    cells_path: Path | None = None
    cached_only: bool = False

    def __post_init__(self) -> None:
        self.out_dir = Path(self.out_dir)
        self.fits_dir = Path(self.fits_dir) if self.fits_dir is not None else self.out_dir / "fits"
        if self.stride_k < 1 or self.val_stride_k < 1:
            raise ValueError(f"stride_k and val_stride_k must be >= 1, got {self.stride_k}, {self.val_stride_k}")
        self._seedsets: dict[int, Any] = {}
        self._eval: dict[str, EvalSet] = {}
        self._negatives: dict[int, Tensor] = {}
        self._cells_path = Path(self.cells_path) if self.cells_path is not None else self.out_dir / "cells.json"
        self._cells: dict[str, Any] = json.loads(self._cells_path.read_text()) if self._cells_path.is_file() else {}

    # data -------------------------------------------------------------
    def videos(self, split: str) -> list[str]:
        from synthaug.data.splits import load_split

        vs = load_split(self.split_file)
        return [v for v in vs.videos[split] if vs.classes.get(v) == self.class_name]

    def seedset(self, n: int) -> Any:
        from synthaug.data.seedset import SeedSet

        if n not in self._seedsets:
            self._seedsets[n] = SeedSet.load(self.seedsets_dir / f"{self.class_name}_{n}")
        return self._seedsets[n]

    def negatives(self, n: int) -> Tensor:
        if n not in self._negatives:
            self._negatives[n] = negative_pool(self.seedset(n), seed=self.seed)
        return self._negatives[n]

    def box_in_window(self, boxes: Any) -> tuple[float, float, float, float]:
        from synthaug.detectors.base import box_in_window_from_boxes

        return box_in_window_from_boxes(torch.as_tensor(np.asarray(boxes), dtype=torch.float32))

    def eval_set(self, split: str) -> EvalSet:
        if split not in self._eval:
            t0 = time.perf_counter()
            k = self.stride_k if split == "test" else self.val_stride_k
            cap = self.max_test_videos if split == "test" else self.max_val_videos
            self._eval[split] = load_eval_set(self.videos(split), self.videos_dir, self.labels_dir, stride_k=k, max_videos=cap)
            es = self._eval[split]
            self.log(f"[{split}] {len(es.stems)} videos, {es.n_frames} frames (k={k}), {es.n_objects} objects, "
                     f"decoded in {time.perf_counter() - t0:.1f}s")
        return self._eval[split]

    def fit_file(self, n: int, distance: str, *, effects: Sequence[str] | None = None, tag: str = "") -> Path:
        """The capture-parameter fit of seed set ``n`` with ``distance`` (fitted now if missing)."""
        name = f"{self.class_name}_{n}_{distance}{('_' + tag) if tag else ''}.json"
        path = self.fits_dir / name  # type: ignore[operator]
        if not path.is_file():
            from synthaug.fit.fitting import FitConfig, fit_seedset

            t0 = time.perf_counter()
            cfg = FitConfig(distance=distance, seed=self.seed, budget=self.fit_budget,
                            effects=None if effects is None else tuple(effects))
            fit_seedset(self.seedsets_dir / f"{self.class_name}_{n}", self.mesh, path, cfg, workers=self.fit_workers)
            self.log(f"fit {name}: {time.perf_counter() - t0:.0f}s")
        return path

    # cells ------------------------------------------------------------
    def _save_cells(self) -> None:
        from synthaug.params import atomic_write_text

        self._cells_path.parent.mkdir(parents=True, exist_ok=True)
        # merge with what another process may have written meanwhile
        if self._cells_path.is_file():
            on_disk = json.loads(self._cells_path.read_text())
            for k, v in on_disk.items():
                self._cells.setdefault(k, {}).update({kk: vv for kk, vv in v.items() if kk not in self._cells.get(k, {})})
        atomic_write_text(self._cells_path, json.dumps(self._cells, indent=1, sort_keys=True) + "\n")

    def cell(
        self,
        key: str,
        kind: str,
        build: Callable[[], dict[str, Any]],
        splits: Sequence[str] = ("test",),
    ) -> dict[str, Any]:
        """Train (once) and evaluate one detector configuration, cached under ``key``.

        The cache key holds the class, detector kind, ``key``, seed, split,
        frame stride and video cap — *not* the pyramid scales or the training
        budgets: use another cells file when changing those.

        Args:
            key: unique name of the training set (the detector kind, class and
                evaluation settings are added to it).
            kind: detector family.
            build: returns ``{"positives", "negatives", "box_in_window"[, "mining_frames", "mining_boxes"]}``.
            splits: evaluation splits (``"test"``, ``"val"``).

        Returns:
            ``{"train": {...}, "<split>": EvalResult json, ...}``.
        """
        _check_kind(kind)
        full = f"{self.class_name}/{kind}/{key}/seed{self.seed}"
        entry = self._cells.setdefault(full, {})
        ek = {s: f"{s}_k{self.stride_k if s == 'test' else self.val_stride_k}_v{self.max_test_videos if s == 'test' else self.max_val_videos}" for s in splits}
        missing = [s for s in splits if ek[s] not in entry]
        if missing and self.cached_only:
            return {"train": entry.get("train", {}), **{s: entry.get(ek[s], {}) for s in splits}}
        if missing:
            t0 = time.perf_counter()
            data = build()
            t_build = time.perf_counter() - t0
            t0 = time.perf_counter()
            det = train_detector(kind, data["positives"], data["negatives"], self.seed, box_in_window=data.get("box_in_window"),
                                 mining_frames=data.get("mining_frames", ()), mining_boxes=data.get("mining_boxes"), options=self.options)
            t_train = time.perf_counter() - t0
            entry["train"] = {"positives": int(data["positives"].shape[0]), "negatives": int(data["negatives"].shape[0]),
                              "build_s": round(t_build, 1), "train_s": round(t_train, 1)}
            for s in missing:
                res = evaluate_on_videos(det, self.eval_set(s), scales=self.scales)
                entry[ek[s]] = res.to_json()
                self.log(f"  {full} [{s}] AP {res.ap:.3f} (IoU.3 {res.ap_iou03:.3f}) pos {entry['train']['positives']} "
                         f"train {t_train:.0f}s eval {res.n_frames / max(res.frames_per_second, 1e-9):.0f}s ({res.frames_per_second:.1f} fps)")
            self._save_cells()
        return {"train": entry.get("train", {}), **{s: entry[ek[s]] for s in splits}}

    # standard training sets --------------------------------------------
    def real_build(self, n: int) -> Callable[[], dict[str, Any]]:
        def build() -> dict[str, Any]:
            ss = self.seedset(n)
            mf, mb = mining_frames(ss, self.options.hog_mining_frames)
            return {"positives": real_positives(ss), "negatives": self.negatives(n), "box_in_window": self.box_in_window(ss.boxes),
                    "mining_frames": mf, "mining_boxes": mb}
        return build

    def perturbed_build(self, n: int, ratio: float) -> Callable[[], dict[str, Any]]:
        def build() -> dict[str, Any]:
            d = self.real_build(n)()
            copies = int(round(ratio))
            d["positives"] = torch.cat([d["positives"], perturb_patches(d["positives"], copies, generator=torch.Generator().manual_seed(self.seed + 1))])
            return d
        return build

    def synthetic_build(self, n: int, ratio: float, distance: str, *, effects: Sequence[str] | None = None,
                        fit_effects: Sequence[str] | None = None, fit_tag: str = "", capture_sampling: str = "seed") -> Callable[[], dict[str, Any]]:
        def build() -> dict[str, Any]:
            d = self.real_build(n)()
            count = int(round(ratio * len(self.seedset(n))))
            fit = self.fit_file(n, distance, effects=fit_effects, tag=fit_tag)
            syn = synthetic_positives(self.seedset(n), self.mesh, fit, count, seed=self.seed + 2, effects=effects,
                                      capture_sampling=capture_sampling)
            d["positives"] = torch.cat([d["positives"], syn])
            return d
        return build


# --------------------------------------------------------------------------- reporting helpers
def _fmt(x: Any) -> str:
    return "–" if x is None else f"{x:.3f}" if isinstance(x, float) else str(x)


def _stem(ctx: ExperimentContext, name: str) -> str:
    """Output file stem: ``name``, or ``name_seed<k>`` for a base seed other than 0."""
    return name if ctx.seed == 0 else f"{name}_seed{ctx.seed}"


def _write_report(ctx: ExperimentContext, name: str, title: str, header: Sequence[str], rows: Sequence[Sequence[Any]],
                  numbers: dict[str, Any], notes: str = "") -> None:
    from synthaug.params import atomic_write_text

    ctx.out_dir.mkdir(parents=True, exist_ok=True)
    lines = [f"## {title}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_fmt(v) for v in r) + " |" for r in rows]
    if notes:
        lines += ["", notes]
    atomic_write_text(ctx.out_dir / f"{_stem(ctx, name)}.md", "\n".join(lines) + "\n")
    atomic_write_text(ctx.out_dir / f"{_stem(ctx, name)}.json", json.dumps(numbers, indent=1, default=str) + "\n")


def _plot(path: Path, kind: Literal["bar", "line"], series: Mapping[str, Mapping[Any, float | None]], *, title: str, xlabel: str,
          ylabel: str = "AP (IoU 0.5)", logx: bool = False, marks: Mapping[str, Any] | None = None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4), dpi=110)
    try:
        if kind == "line":
            for label, pts in series.items():
                xs = [x for x in pts if pts[x] is not None]  # missing cells: the line joins the measured points
                ys = [pts[x] for x in xs]
                xp = [x + 1 for x in xs] if logx else xs
                ax.plot(xp, ys, marker="o", label=label)
                if marks and label in marks and pts.get(marks[label]) is not None:
                    x = marks[label]
                    ax.plot([x + 1 if logx else x], [pts[x]], marker="*", markersize=14, color="k", linestyle="none")
            if logx:
                ax.set_xscale("log")
                ax.set_xlabel(xlabel + " (+1, log)")
            else:
                ax.set_xlabel(xlabel)
        else:
            groups = list(series.keys())
            cats = list(dict.fromkeys(c for g in series.values() for c in g))
            width = 0.8 / max(len(cats), 1)
            for j, c in enumerate(cats):
                ys = [np.nan if series[g].get(c) is None else series[g][c] for g in groups]
                ax.bar(np.arange(len(groups)) + (j - (len(cats) - 1) / 2) * width, ys, width, label=str(c))
            ax.set_xticks(np.arange(len(groups)), groups)
            ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_ylim(0, max(0.05, min(1.0, 1.15 * max([v for s in series.values() for v in s.values() if v is not None] or [0.05]))))
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path)
    finally:
        plt.close(fig)


def _ap(cell: dict[str, Any], split: str = "test", key: str = "ap") -> float | None:
    return cell.get(split, {}).get(key)


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
    from synthaug.params import atomic_write_text

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
    from synthaug.params import CaptureParams

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
