"""A trained detector's own box errors, measured on its training videos and taken out of its boxes.

The box maps of :mod:`synthaug.detectors.boxes` and :mod:`~synthaug.detectors.box_cnn` are fitted on jittered
boxes around the labelled ones, before any detector exists, so they serve every family alike. A trained detector
does not err like the jitter: on the halmstad drone validation videos (HOG, 100 seeds, 10 training seeds, stop 73)
its mapped boxes on drones of 24-96 px are a median 12-17 % too small (log-size -0.13 to -0.19), and one trained
with synthetic positives misses IoU 0.5 on the 48-96 px drones it finds at IoU 0.3 more often (28 % against 20 %).

:func:`calibrate_boxes` runs the detector (box map included) over labelled frames of its training videos, matches
its detections to the labelled boxes as the evaluation does (by decreasing score, each box taken once, IoU at
least ``min_iou``), and fits the deltas that remain (:func:`~synthaug.detectors.boxes.encode_deltas` of the
labelled box against the mapped one) as a linear function of the mapped box's log size by least squares
(:func:`fit_calibration`). :class:`CalibratedBoxRegressor` applies the box map, then that correction: R-CNN's box
regression trained on the detector's own detections (Girshick et al. 2014, appendix C), in its simplest form.

Example:
    >>> from synthaug.detectors.boxes import BoxRegressor
    >>> cal = CalibratedBoxRegressor(BoxRegressor.identity(), torch.tensor([[0.0, 0.0, 0.1, 0.1], [0.0] * 4]))
    >>> [round(v, 2) for v in cal.refine(torch.rand(1, 1, 64, 64), torch.tensor([[10., 10., 30., 30.]]))[0].tolist()]
    [8.95, 8.95, 31.05, 31.05]
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch
from torch import Tensor
from torchvision.ops import box_convert, box_iou

from synthaug._checks import one_of
from synthaug.detectors.boxes import DeltaRegressor, decode_deltas, encode_deltas

__all__ = ["CALIBRATION_FORMS", "CALIBRATION_VERSION", "CalibratedBoxRegressor", "calibrate_boxes", "check_form",
           "detection_pairs", "fit_calibration", "size_features"]

CALIBRATION_VERSION = 1
"""Part of the key of a cached cell scored with a calibrated detector: bump it when :func:`calibrate_boxes` changes."""

CALIBRATION_FORMS = ("regression", "inverse")
"""How :func:`fit_calibration` fits the size correction: ``"regression"`` (the default: the labelled box's size given
the detected one, least squares: it pulls every box towards the typical size of the training videos' objects) or
``"inverse"`` (the detected size given the labelled one, inverted: the classical calibration estimator, unbiased for
an object of any size when the detector errs on its training videos as it errs elsewhere). Measured on the halmstad
drone test videos (the CNN, 100 seeds, 3 training seeds, the same stored detectors; stop 76,
``results/synthetic/box_calibration/README.md``): inverse − regression −0.137 [−0.193, −0.085] AP@0.5 for real
only and −0.133 [−0.174, −0.093] with synthetic positives, 0 of 14 videos up. The detector's boxes are smaller on the
test videos than on its training videos, so the inverse fit's boxes came out a median 8 % too small there, where
the regression's lean towards mid sizes happens to undo that."""


def check_form(form: str, name: str = "form") -> str:
    """``form`` if it is one of :data:`CALIBRATION_FORMS`; else a ValueError naming ``name``."""
    return one_of(form, CALIBRATION_FORMS, name)


REFERENCE_SIDE = 32.0
"""The box side (pixels) where the correction's size feature is 0: ``log(side / REFERENCE_SIDE)``."""


def size_features(boxes_xyxy: Tensor) -> Tensor:
    """``[1, log(sqrt(w h) / REFERENCE_SIDE)]`` of each box, the correction's regressors.

    Shape:
        - boxes_xyxy: (N, 4)
        - output: (N, 2) float64
    """
    w = (boxes_xyxy[:, 2] - boxes_xyxy[:, 0]).double().clamp_min(1e-6)
    h = (boxes_xyxy[:, 3] - boxes_xyxy[:, 1]).double().clamp_min(1e-6)
    return torch.stack([torch.ones_like(w), 0.5 * torch.log(w * h) - np.log(REFERENCE_SIDE)], dim=1)


@dataclass
class CalibratedBoxRegressor(DeltaRegressor):
    """A box map followed by a detector's own correction: deltas ``size_features(box) @ coef`` on the mapped box.

    Attributes:
        base: the box map (any regressor with ``refine``; None: the detector's window boxes are corrected).
        coef: ``(2, 4)`` correction of ``(dx, dy, dw, dh)``: intercept row, then the log-size row.
        meta: how it was fitted (:func:`calibrate_boxes`).
    """

    base: Any
    coef: Tensor
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.coef = torch.as_tensor(self.coef, dtype=torch.float64)
        if self.coef.shape != (2, 4) or not bool(torch.isfinite(self.coef).all()):
            raise ValueError(f"coef must be a finite (2, 4) tensor, got shape {tuple(self.coef.shape)}")

    def refine(self, image: Tensor, boxes_xyxy: Tensor) -> Tensor:
        """The base map's boxes, then the correction (XYXY, same order).

        Shape:
            - image: (1, 1, H, W) or (H, W); boxes_xyxy: (N, 4); output: (N, 4)
        """
        if boxes_xyxy.shape[0] == 0:
            return boxes_xyxy
        mapped = boxes_xyxy.float() if self.base is None else self.base.refine(image, boxes_xyxy).float()
        return decode_deltas(mapped, size_features(mapped) @ self.coef)

    def state_dict(self) -> dict[str, Any]:
        return {"model": "calibrated", "base": None if self.base is None else self.base.state_dict(),
                "coef": self.coef.clone(), "meta": dict(self.meta)}

    @classmethod
    def from_state_dict(cls, state: dict[str, Any], *,
                        rebuild: Callable[[dict[str, Any]], Any]) -> "CalibratedBoxRegressor":
        """Rebuild from :meth:`state_dict`; ``rebuild`` turns the base map's state into a regressor
        (:func:`~synthaug.detectors.box_cnn.regressor_from_state_dict`, which passes itself)."""
        try:
            base = None if state["base"] is None else rebuild(state["base"])
            return cls(base, torch.as_tensor(state["coef"]), dict(state.get("meta") or {}))
        except (KeyError, TypeError) as e:
            raise ValueError(f"calibrated box regressor state is missing or has a malformed field "
                             f"({type(e).__name__}: {e})") from e


def fit_calibration(boxes_xyxy: Tensor, targets_xyxy: Tensor, *, form: str = "regression") -> Tensor:
    """``coef`` (2, 4) of ``encode_deltas(boxes, targets) ~ size_features(boxes) @ coef``.

    ``form="regression"`` fits every column by least squares on the detected box's size: the best guess of the
    labelled box given the detected one, on the training videos' mix of sizes. Where the detected size is noisy,
    that guess leans towards the sizes the training videos hold most (regression to the mean): on the halmstad
    drone test videos, which hold more small drones than the training videos, the CNN's boxes of drones < 24 px
    came out a median 20 % too large (stop 76, ``results/synthetic/box_calibration/README.md``).

    ``form="inverse"`` keeps the position columns (dx, dy) of the least-squares fit and fits the size the other
    way round: ``f(detected) = a + b f(labelled)`` (``f`` the log-size feature of :func:`size_features`) by least
    squares, then inverts it, ``f(labelled) = (f(detected) - a) / b``: the width and height deltas get the slope
    ``1 / b - 1`` and the intercepts that leave their mean residual at 0. That estimate is unbiased for an object of
    any size whatever the training videos' mix of sizes (the classical calibration estimator), at the price of a
    larger spread (``1 / b``). With ``b <= 0.25`` (detected and labelled sizes barely related) the size slope is
    left at 0.

    Shape:
        - boxes_xyxy, targets_xyxy: (N, 4), N >= 2 with at least two box sizes
        - output: (2, 4) float64

    Example:
        >>> b = torch.tensor([[0., 0., 10., 10.], [0., 0., 20., 20.], [0., 0., 40., 40.]])
        >>> t = torch.tensor([[0., 0., 10., 10.], [0., 0., 22., 22.], [0., 0., 48., 48.]])  # larger boxes too small
        >>> [round(v, 3) for v in fit_calibration(b, t, form="inverse")[:, 2].tolist()]  # f(det) = a + 0.88 f(lab)
        [0.154, 0.132]
    """
    check_form(form)
    if boxes_xyxy.shape[0] < 2:
        raise ValueError(f"fit_calibration needs at least 2 matched boxes, got {boxes_xyxy.shape[0]}")
    x = size_features(boxes_xyxy)
    y = encode_deltas(boxes_xyxy.double(), targets_xyxy.double())
    if float(x[:, 1].std()) < 1e-9:  # one size: the intercept alone
        return torch.cat([y.mean(0, keepdim=True), torch.zeros(1, 4, dtype=torch.float64)])
    coef = torch.linalg.lstsq(x, y).solution
    if form == "inverse":
        f_det, f_lab = x[:, 1], size_features(targets_xyxy)[:, 1]
        var = float(((f_lab - f_lab.mean()) ** 2).mean())
        b = float(((f_lab - f_lab.mean()) * (f_det - f_det.mean())).mean()) / var if var > 1e-12 else 0.0
        slope = 1.0 / b - 1.0 if b > 0.25 else 0.0
        coef[1, 2:] = slope
        coef[0, 2:] = y[:, 2:].mean(0) - slope * f_det.mean()
    return coef


def detection_pairs(detections_xywhs: np.ndarray | Tensor, labelled_xywh: np.ndarray | Tensor | None, *,
                    min_iou: float = 0.3) -> tuple[Tensor, Tensor]:
    """The detections matched to labelled boxes as the evaluation matches them, and their labelled boxes.

    In decreasing score, each detection takes the unmatched labelled box it overlaps most, if that IoU is at
    least ``min_iou`` (PASCAL VOC's greedy rule, :func:`synthaug.evaluate.ap.match_detections`).

    Args:
        detections_xywhs: ``(D, 5)`` ``[x, y, w, h, score]`` (any order).
        labelled_xywh: ``(G, 4)`` or None.

    Returns:
        ``(detections, labelled)``: ``(M, 4)`` XYXY each, row ``i`` matched to row ``i``.
    """
    d = torch.as_tensor(np.asarray(detections_xywhs, dtype=np.float64)).reshape(-1, 5)
    g = torch.as_tensor(np.asarray(labelled_xywh if labelled_xywh is not None else np.zeros((0, 4)),
                                   dtype=np.float64)).reshape(-1, 4)
    if d.shape[0] == 0 or g.shape[0] == 0:
        return torch.zeros(0, 4, dtype=torch.float64), torch.zeros(0, 4, dtype=torch.float64)
    d = d[torch.argsort(d[:, 4], descending=True, stable=True)]
    db, gb = box_convert(d[:, :4], "xywh", "xyxy"), box_convert(g, "xywh", "xyxy")
    iou = box_iou(db, gb)
    taken = torch.zeros(gb.shape[0], dtype=torch.bool)
    rows, cols = [], []
    for i in range(db.shape[0]):
        o = iou[i].masked_fill(taken, -1.0)
        j = int(torch.argmax(o))
        if float(o[j]) >= min_iou:
            taken[j] = True
            rows.append(i)
            cols.append(j)
    return db[rows], gb[cols]


def calibrate_boxes(detector: Any, frames: Iterable[Any], *, scales: Sequence[float] | None = None,
                    nms_iou: float = 0.3, max_detections: int = 100, min_iou: float = 0.3,
                    min_pairs: int = 20, form: str = "regression",
                    detect: Callable[..., Tensor]) -> CalibratedBoxRegressor:
    """Fit a detector's own box correction on labelled frames (its training videos' frames).

    Args:
        detector: a trained patch detector; its ``box_regressor`` (if any) is the base map.
        frames: items with ``image`` (uint8 or float gray ``(H, W)``) and ``boxes`` (``(G, 4)`` XYWH or None), e.g.
            :class:`~synthaug.detectors.frames.VideoFrames` of the training videos.
        scales, nms_iou, max_detections: the detection's, as scored (:func:`~synthaug.detectors.sliding.detect_multiscale`).
        min_iou: the least IoU of a detection matched to a labelled box (the protocol's lowest, 0.3).
        min_pairs: fewer matched detections than this is an error (nothing to fit reliably).
        form: how the size correction is fitted (:data:`CALIBRATION_FORMS`, :func:`fit_calibration`).
        detect: :func:`~synthaug.detectors.sliding.detect_multiscale` (passed in: this module stays below it).

    Returns:
        The :class:`CalibratedBoxRegressor` (set it as ``detector.box_regressor`` to use it); its ``meta`` holds
        the number of frames and pairs, the residual deltas' medians before and after, and the seconds.

    Raises:
        ValueError: fewer than ``min_pairs`` matched detections, or an unknown ``form``.
    """
    check_form(form)
    t0 = time.perf_counter()
    base = getattr(detector, "box_regressor", None)
    found: list[Tensor] = []
    labelled: list[Tensor] = []
    n_frames = 0
    for item in frames:
        if item.boxes is None or np.asarray(item.boxes).size == 0:
            continue
        image = torch.as_tensor(np.asarray(item.image))
        image = image.float() / 255.0 if image.dtype == torch.uint8 else image.float()
        det = detect(detector, image, **({} if scales is None else {"scales": list(scales)}),
                                nms_iou=nms_iou, max_detections=max_detections)
        p, g = detection_pairs(det.numpy(), item.boxes, min_iou=min_iou)
        found.append(p)
        labelled.append(g)
        n_frames += 1
    p = torch.cat(found) if found else torch.zeros(0, 4, dtype=torch.float64)
    g = torch.cat(labelled) if labelled else torch.zeros(0, 4, dtype=torch.float64)
    if p.shape[0] < min_pairs:
        raise ValueError(f"calibrate_boxes: {p.shape[0]} detections matched a labelled box in {n_frames} frames "
                         f"(at least {min_pairs} needed)")
    coef = fit_calibration(p, g, form=form)
    before = encode_deltas(p, g)
    after = encode_deltas(decode_deltas(p.float(), size_features(p) @ coef).double(), g)
    meta = {"frames": n_frames, "pairs": int(p.shape[0]), "min_iou": float(min_iou), "form": form,
            "median_deltas_before": [round(float(v), 4) for v in before.median(0).values],
            "median_deltas_after": [round(float(v), 4) for v in after.median(0).values],
            "coef": [[round(float(v), 6) for v in row] for row in coef], "seconds": round(time.perf_counter() - t0, 1)}
    return CalibratedBoxRegressor(base, coef, meta)
