"""Boxes in the annotators' convention, learned by a small CNN on the box's context pixels.

:class:`CNNBoxRegressor` has the interface of :class:`~synthaug.detectors.boxes.BoxRegressor`
(``refine(image, boxes)``, ``predict``, ``state_dict``) and the same training data (boxes jittered
around the labelled boxes of the training videos, :func:`~synthaug.detectors.boxes.jittered_samples`,
R-CNN deltas as targets), but reads the box's square context (the box's longest side x ``context``,
resampled to ``size x size`` with :func:`torchvision.ops.roi_align`) as pixels, each crop standardised
(zero mean, unit deviation), through three conv-BN-ReLU-pool stages and two linear layers, trained with a
smooth-L1 loss, horizontal flips (``dx`` changes sign) and a one-cycle AdamW schedule; the epoch kept is
the one with the least squared delta error on held-out *videos* (a fifth of them).

Why beside the ridge regressor: measured on the halmstad drone validation split (one HOG and one CNN
detector, 100 seeds, training seed 0; the same raw detections; the scripts in
``results/learning_curve/drone_box_cnn/offline/``), the ridge map on HOG cells explains about half the delta variance (held-out MSE 0.035 vs
0.067 without regression) and fails on enlarged drones, where the detector's window covers ~0.6 of the
drone: frame AP@0.5 HOG x1 0.671 / x2 0.335, CNN 0.638 / 0.490. This regressor (held-out MSE 0.023):
HOG 0.667 / 0.567, CNN 0.666 / 0.616. Fitting takes ~2 min on one thread (35k crops, 8 epochs).

Example:
    >>> import torch
    >>> reg = CNNBoxRegressor.untrained(seed=0)
    >>> reg.refine(torch.rand(1, 1, 64, 64), torch.tensor([[10., 10., 40., 30.]])).shape
    torch.Size([1, 4])
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn
from torchvision.ops import roi_align

from synthaug.detectors.boxes import BoxRegressor, DeltaRegressor, _plain, context_rois, encode_deltas, jittered_samples

__all__ = ["CNNBoxRegressor", "EnsembleBoxRegressor", "box_net", "regressor_from_state_dict"]


def box_net(size: int = 32) -> nn.Sequential:
    """The regressor's network: ``(N, 1, size, size)`` standardised crops -> ``(N, 4)`` deltas (minus their mean)."""
    if size % 8:
        raise ValueError(f"size must be a multiple of 8, got {size}")

    def stage(cin: int, cout: int) -> list[nn.Module]:
        return [nn.Conv2d(cin, cout, 3, padding=1), nn.BatchNorm2d(cout), nn.ReLU(), nn.MaxPool2d(2)]

    return nn.Sequential(*stage(1, 16), *stage(16, 32), *stage(32, 64), nn.Flatten(),
                         nn.Linear(64 * (size // 8) ** 2, 64), nn.ReLU(), nn.Linear(64, 4))


@dataclass
class CNNBoxRegressor(DeltaRegressor):
    """A CNN from a box's context pixels to the annotators' box (module docstring).

    Attributes:
        net: :func:`box_net` (kept in eval mode).
        mean_y: ``(4,)`` mean training deltas (the net predicts the rest).
        context: the crop is the box's longest side times this, centred, square.
        size: the crop is resampled to ``size x size`` pixels.
        meta: how it was fitted (samples, videos, held-out errors per epoch, the epoch kept, seconds).
    """

    net: nn.Sequential
    mean_y: Tensor
    context: float = 2.0
    size: int = 32
    meta: dict[str, Any] | None = None

    # ------------------------------------------------------------------ features and prediction
    @staticmethod
    def crops(image: Tensor, boxes_xyxy: Tensor, *, context: float = 2.0, size: int = 32) -> Tensor:
        """Each box's square context, resampled and standardised.

        Shape:
            - image: (1, 1, H, W) float in [0, 1]
            - boxes_xyxy: (N, 4)
            - output: (N, 1, size, size)
        """
        c = roi_align(image.float(), context_rois(boxes_xyxy, context), (size, size), spatial_scale=1.0,
                      sampling_ratio=2, aligned=True)
        mean = c.mean((1, 2, 3), keepdim=True)
        return (c - mean) / (c.std((1, 2, 3), keepdim=True) + 0.02)

    @torch.no_grad()
    def predict(self, image: Tensor, boxes_xyxy: Tensor) -> Tensor:
        """Deltas (:func:`~synthaug.detectors.boxes.encode_deltas` convention) for each box, ``(N, 4)``."""
        if boxes_xyxy.shape[0] == 0:
            return boxes_xyxy.new_zeros(0, 4)
        self.net.eval()
        return self.net(self.crops(image, boxes_xyxy, context=self.context, size=self.size)) + self.mean_y.float()

    @classmethod
    def untrained(cls, *, seed: int = 0, context: float = 2.0, size: int = 32) -> "CNNBoxRegressor":
        """A regressor with freshly initialised weights (drawn from ``seed``) and zero mean deltas."""
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(int(seed))
            net = box_net(size)
        return cls(net.eval(), torch.zeros(4), float(context), int(size), {"untrained": True})

    # ------------------------------------------------------------------ fitting
    @classmethod
    def fit(
        cls,
        frames: Iterable[Any],
        *,
        aspect: float,
        jitters: int = 32,
        seed: int = 0,
        epochs: int = 8,
        batch_size: int = 256,
        lr: float = 3e-3,
        held_out: float = 0.2,
        context: float = 2.0,
        size: int = 32,
        log_size_sigma: float = 0.35,
        shift_sigma: float = 0.12,
    ) -> "CNNBoxRegressor":
        """Learn the map from jittered detector boxes to the labelled boxes of some frames.

        Args:
            frames: as :meth:`~synthaug.detectors.boxes.BoxRegressor.fit` (``video`` groups the held-out split).
            aspect: width / height of the boxes the detector reports.
            jitters: boxes drawn around each labelled box.
            seed: seed of the jitter draws, the held-out videos, the initial weights, the batches and flips.
            epochs: passes over the training crops; the epoch with the least held-out error is kept.
            batch_size, lr: mini-batch size and the one-cycle schedule's peak learning rate (AdamW).
            held_out: fraction of the videos (at least one) held out to choose the epoch; with fewer than 5
                videos, or 0, none is held out and the last epoch is kept (``meta["held_out_mse"]`` is None).
            context, size: the crop (:meth:`crops`).
            log_size_sigma, shift_sigma: the jitter (:func:`~synthaug.detectors.boxes.jitter_boxes`).

        Raises:
            ValueError: when the frames hold no labelled box, or a bad setting.
        """
        if epochs < 1 or batch_size < 1 or not 0 <= held_out < 1:
            raise ValueError(f"need epochs >= 1, batch_size >= 1, 0 <= held_out < 1; got {epochs}, {batch_size}, {held_out}")
        t0 = time.perf_counter()
        xs, ys, groups = [], [], []
        for image, p, g, video in jittered_samples(frames, jitters, aspect=aspect, seed=seed,
                                                   log_size_sigma=log_size_sigma, shift_sigma=shift_sigma):
            xs.append(cls.crops(image, p, context=context, size=size))
            ys.append(encode_deltas(p, g))
            groups += [video] * p.shape[0]
        if not xs:
            raise ValueError("CNNBoxRegressor.fit: the frames hold no labelled box to learn from")
        x, y = torch.cat(xs), torch.cat(ys).float()
        gen = torch.Generator().manual_seed(int(seed) + 1)
        names = sorted(set(groups))
        n_hold = max(1, int(round(held_out * len(names)))) if len(names) >= 5 and held_out > 0 else 0
        hold = {names[i] for i in torch.randperm(len(names), generator=gen)[:n_hold].tolist()}
        test = torch.as_tensor(np.isin(np.asarray(groups), sorted(hold)))
        train, has_test = ~test, bool(test.any())
        mean_y = y[train].mean(0)
        xt, yt = x[train], y[train] - mean_y
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(int(seed))
            net = box_net(size)
        opt = torch.optim.AdamW(net.parameters(), lr=lr, weight_decay=1e-4)
        steps = epochs * ((xt.shape[0] + batch_size - 1) // batch_size)
        sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=lr, total_steps=steps)
        history: list[float] = []
        best: tuple[float, int, dict[str, Tensor]] | None = None
        for epoch in range(epochs):
            net.train()
            perm = torch.randperm(xt.shape[0], generator=gen)
            for i in range(0, perm.numel(), batch_size):
                j = perm[i:i + batch_size]
                xb, yb = xt[j], yt[j].clone()
                flip = torch.rand(j.numel(), generator=gen) < 0.5  # mirrored crop: the x shift changes sign
                xb = torch.where(flip[:, None, None, None], xb.flip(-1), xb)
                yb[flip, 0] = -yb[flip, 0]
                loss = nn.functional.smooth_l1_loss(net(xb), yb, beta=0.1)
                opt.zero_grad()
                loss.backward()
                opt.step()
                sched.step()
            net.eval()
            with torch.no_grad():
                err = float(((net(x[test]) + mean_y - y[test]) ** 2).mean()) if has_test else float("inf")
            history.append(err)
            if best is None or not has_test or err < best[0]:
                best = (err, epoch, {k: v.clone() for k, v in net.state_dict().items()})
        assert best is not None
        net.load_state_dict(best[2])
        meta = {"samples": int(x.shape[0]), "videos": len(names), "held_out_videos": sorted(hold), "aspect": float(aspect),
                "jitters": int(jitters), "seed": int(seed), "epochs": int(epochs), "epoch_kept": best[1],
                "held_out_mse": history if has_test else None,
                "held_out_mse_no_regression": float(((y[test] - mean_y) ** 2).mean()) if has_test else None,
                "log_size_sigma": float(log_size_sigma), "shift_sigma": float(shift_sigma),
                "seconds": round(time.perf_counter() - t0, 1)}
        return cls(net.eval(), mean_y, float(context), int(size), meta)

    # ------------------------------------------------------------------ serialisation
    def state_dict(self) -> dict[str, Any]:
        """Tensors and plain types only (loads with ``torch.load(weights_only=True)``)."""
        return {"model": "cnn", "net": {k: v.clone() for k, v in self.net.state_dict().items()},
                "mean_y": self.mean_y.clone(), "context": float(self.context), "size": int(self.size),
                "meta": _plain(self.meta or {})}

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> "CNNBoxRegressor":
        """Rebuild from :meth:`state_dict`; a malformed state is a ValueError."""
        try:
            size = int(state["size"])
            net = box_net(size)
            net.load_state_dict(state["net"])
            reg = cls(net.eval(), torch.as_tensor(state["mean_y"], dtype=torch.float32), float(state["context"]), size,
                      dict(state.get("meta") or {}))
        except (KeyError, TypeError, RuntimeError) as e:
            raise ValueError(f"CNN box regressor state is missing or has a malformed field ({type(e).__name__}: {e})") from e
        if reg.mean_y.shape != (4,):
            raise ValueError(f"CNN box regressor state has mean_y of shape {tuple(reg.mean_y.shape)}; expected (4,)")
        return reg


@dataclass
class EnsembleBoxRegressor(DeltaRegressor):
    """The mean of several box regressors' deltas (``TrainOptions.box_model = "ensemble"``: the ridge map and the CNN).

    Measured on the halmstad drone validation split (one detector per family, 100 seeds, training seed 0, the same
    raw detections), frame AP@0.5 x1 / x2: HOG ridge 0.671 / 0.335, CNN map 0.667 / 0.567, the mean of both
    0.686 / 0.456; CNN detector 0.638 / 0.490, 0.666 / 0.616, 0.676 / 0.597.

    Example:
        >>> from synthaug.detectors.boxes import BoxRegressor
        >>> reg = EnsembleBoxRegressor([BoxRegressor.identity(), BoxRegressor.identity()])
        >>> reg.refine(torch.rand(1, 1, 64, 64), torch.tensor([[10., 10., 40., 30.]])).tolist()
        [[10.0, 10.0, 40.0, 30.0]]
    """

    parts: list[Any]

    def __post_init__(self) -> None:
        if not self.parts:
            raise ValueError("EnsembleBoxRegressor needs at least one regressor")

    @property
    def meta(self) -> dict[str, Any]:
        return {"parts": [dict(getattr(p, "meta", None) or {}) for p in self.parts]}

    def predict(self, image: Tensor, boxes_xyxy: Tensor) -> Tensor:
        """The mean of the parts' deltas, ``(N, 4)``."""
        return torch.stack([p.predict(image, boxes_xyxy).float() for p in self.parts]).mean(0)

    def state_dict(self) -> dict[str, Any]:
        return {"model": "ensemble", "parts": [p.state_dict() for p in self.parts]}

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> "EnsembleBoxRegressor":
        parts = state.get("parts")
        if not isinstance(parts, list) or not parts:
            raise ValueError("ensemble box regressor state is missing or has a malformed field (parts)")
        return cls([regressor_from_state_dict(p) for p in parts])


def regressor_from_state_dict(state: dict[str, Any]) -> Any:
    """A box regressor rebuilt from its ``state_dict()``: :class:`~synthaug.detectors.boxes.BoxRegressor` (ridge;
    also a state without ``"model"``, as files written before the CNN), :class:`CNNBoxRegressor` (``"cnn"``) or
    :class:`EnsembleBoxRegressor` (``"ensemble"``) or :class:`~synthaug.detectors.box_calibration.CalibratedBoxRegressor`
    (``"calibrated"``); a malformed state is a ValueError."""
    if not isinstance(state, dict):
        raise ValueError(f"box regressor state must be a dict, got {type(state).__name__}")
    model = state.get("model", "ridge")
    if model == "ridge":
        return BoxRegressor.from_state_dict(state)
    if model == "cnn":
        return CNNBoxRegressor.from_state_dict(state)
    if model == "ensemble":
        return EnsembleBoxRegressor.from_state_dict(state)
    if model == "calibrated":
        from synthaug.detectors.box_calibration import CalibratedBoxRegressor

        return CalibratedBoxRegressor.from_state_dict(state, rebuild=regressor_from_state_dict)
    raise ValueError(f"box regressor state has model {model!r}; expected 'ridge', 'cnn', 'ensemble' or 'calibrated'")
