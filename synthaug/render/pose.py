"""Pose conventions.

The object rotation in the camera frame is ``R = Rz(γ) · Ry(β) · Rx(α)``:
α and β turn the object out of the image plane (they change *which* view the
camera sees), γ turns it about the optical axis (an in-plane image rotation).
Camera frame (OpenGL): x right, y up, z toward the viewer; the camera is
orthographic, so (γ, t_x, t_y) act on the image exactly as a 2-D rigid motion.
Image convention: x right, y down; t_x, t_y are fractions of the patch side
(t_y > 0 moves the object down). A positive γ turns the object
counter-clockwise as seen in the image.

Example:
    >>> import numpy as np
    >>> R = rotation_matrix(0.0, 0.0, np.pi / 2)
    >>> np.round(R @ [1.0, 0.0, 0.0], 6).tolist()
    [0.0, 1.0, 0.0]
"""

from __future__ import annotations

import numpy as np


def rotation_matrix(alpha: float, beta: float, gamma: float) -> np.ndarray:
    """R = Rz(γ) Ry(β) Rx(α), float64 (3, 3)."""
    ca, sa = np.cos(alpha), np.sin(alpha)
    cb, sb = np.cos(beta), np.sin(beta)
    cg, sg = np.cos(gamma), np.sin(gamma)
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rz = np.array([[cg, -sg, 0], [sg, cg, 0], [0, 0, 1]])
    return rz @ ry @ rx


def rotation_matrices(alpha: np.ndarray, beta: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """Batched :func:`rotation_matrix`: (N,) arrays -> (N, 3, 3)."""
    return np.stack([rotation_matrix(a, b, g) for a, b, g in zip(np.ravel(alpha), np.ravel(beta), np.ravel(gamma))])
