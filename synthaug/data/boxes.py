"""Boxes: XYXY inside, XYWH only at the file edges (label files, detection files).

The one home of box conversion and box IoU for the package; both are
torchvision's (:func:`torchvision.ops.box_convert`, :func:`torchvision.ops.box_iou`),
the ones detection's NMS uses, here on numpy arrays in float64.

Example:
    >>> import numpy as np
    >>> a = xywh_to_xyxy(np.array([[0, 0, 2, 2]]))
    >>> a.tolist()
    [[0.0, 0.0, 2.0, 2.0]]
    >>> box_iou(a, xywh_to_xyxy(np.array([[1, 0, 2, 2], [5, 5, 1, 1]]))).round(4)
    array([[0.3333, 0.    ]])
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

__all__ = ["box_iou", "xywh_to_xyxy", "xyxy_to_xywh"]


def _boxes64(boxes: Any) -> torch.Tensor:
    return torch.as_tensor(np.asarray(boxes, dtype=np.float64).reshape(-1, 4))


def xywh_to_xyxy(boxes_xywh: Any) -> np.ndarray:
    """``[x, y, w, h]`` boxes (any array-like of 4·N numbers) as float64 ``(N, 4)`` ``[x1, y1, x2, y2]``."""
    from torchvision.ops import box_convert

    return box_convert(_boxes64(boxes_xywh), "xywh", "xyxy").numpy()


def xyxy_to_xywh(boxes_xyxy: Any) -> np.ndarray:
    """``[x1, y1, x2, y2]`` boxes as float64 ``(N, 4)`` ``[x, y, w, h]``."""
    from torchvision.ops import box_convert

    return box_convert(_boxes64(boxes_xyxy), "xyxy", "xywh").numpy()


def box_iou(a_xyxy: Any, b_xyxy: Any) -> np.ndarray:
    """Pairwise IoU of XYXY boxes, ``(K, 4) x (M, 4) -> (K, M)`` float64.

    A pair of empty boxes (union 0, which torchvision gives as NaN) has IoU 0, so
    it never matches at any threshold and never wins an ``argmax``.
    """
    from torchvision.ops import box_iou as tv_box_iou

    return torch.nan_to_num(tv_box_iou(_boxes64(a_xyxy), _boxes64(b_xyxy)), nan=0.0).numpy()
