"""The experiment runner: data locations, budgets, the standard training sets, and the cell cache.

An experiment is a set of *cells* (detector x training set x evaluation
split). :meth:`ExperimentContext.cell` trains a detector once and scores it on
the test/validation videos (:mod:`synthaug.evaluate.videos`); its result is
stored in ``<out>/cells.json`` (or a shared ``cells_path``) under a key naming
the class, detector, training set, seed, split, frame stride and video cap, so
a rerun — or another experiment sharing the cell — reuses it: an interrupted
run resumes. Every draw comes from a generator seeded by the context's
``seed`` (and a per-set offset), so a cell is deterministic given its key.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import torch
from torch import Tensor

from synthaug._io import atomic_write_text
from synthaug.data.seedset import SeedSet
from synthaug.data.splits import load_split
from synthaug.detectors.base import box_in_window_from_boxes
from synthaug.detectors.training import TrainOptions, check_kind, train_detector
from synthaug.detectors.training_sets import mining_frames, negative_pool, real_positives, synthetic_positives
from synthaug.effects.perturb import with_perturbed_copies
from synthaug.evaluate.videos import EvalSet, evaluate_on_videos, load_eval_set
from synthaug.fit.fitting import FitConfig, fit_seedset

__all__ = ["ExperimentContext"]


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
    stride_k: int = 15  # the values `synthaug experiment` has always run with (it read 15 / 30 while these said 10 / 20)
    val_stride_k: int = 30
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
        vs = load_split(self.split_file)
        return [v for v in vs.videos[split] if vs.classes.get(v) == self.class_name]

    def seedset(self, n: int) -> Any:
        if n not in self._seedsets:
            self._seedsets[n] = SeedSet.load(self.seedsets_dir / f"{self.class_name}_{n}")
        return self._seedsets[n]

    def negatives(self, n: int) -> Tensor:
        if n not in self._negatives:
            self._negatives[n] = negative_pool(self.seedset(n), seed=self.seed)
        return self._negatives[n]

    def box_in_window(self, boxes: Any) -> tuple[float, float, float, float]:
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
            t0 = time.perf_counter()
            cfg = FitConfig(distance=distance, seed=self.seed, budget=self.fit_budget,
                            effects=None if effects is None else tuple(effects))
            fit_seedset(self.seedsets_dir / f"{self.class_name}_{n}", self.mesh, path, cfg, workers=self.fit_workers)
            self.log(f"fit {name}: {time.perf_counter() - t0:.0f}s")
        return path

    # cells ------------------------------------------------------------
    def _save_cells(self) -> None:
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
        check_kind(kind)
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
            d["positives"] = with_perturbed_copies(d["positives"], copies, seed=self.seed + 1)
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
