"""A generated panning video whose true background is known.

A procedural panorama is filmed by a virtual pan/tilt camera (a slowly
rotating, translating homography); an object layer is composited on every
frame. The writer saves what a user would bring (a video and per-frame boxes in
the halmstad label format) *and* the truth (the object-free frames), so that
background estimation can be checked against the real answer.

Layout written under ``out_dir``::

    videos/<name>.mp4     8-bit grayscale video (OpenCV, mp4v)
    labels/<name>.json    {"video", "class", "box_format": "xywh_pixels", "boxes"}
    truth/<name>.npz      backgrounds (T, H, W) uint8, frames (T, H, W) uint8 before
                          encoding, boxes (T, 4) float32, homographies (T, 3, 3)

Example:
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     v = make_panning_video(d, n_frames=4, size=(160, 128), seed=0)
    ...     v.backgrounds.shape, v.boxes.shape, v.video_path.name
    ((4, 128, 160), (4, 4), 'V_SYNTH_000.mp4')
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Literal

import numpy as np

__all__ = ["SynthVideo", "make_panning_video", "make_panorama", "dark_quadcopter", "ObjectFn"]

#: ``object_fn(frame_index, rng) -> (layer, alpha)``: layer ``(h, w)`` float in
#: [0, 255] (grayscale), alpha ``(h, w)`` float in [0, 1]. The layer is pasted
#: centred on the object's path; the box is the bounding box of ``alpha > 0.05``.
ObjectFn = Callable[[int, np.random.Generator], "tuple[np.ndarray, np.ndarray]"]


@dataclass
class SynthVideo:
    """Paths and truth of a generated video.

    Attributes:
        video_path: the mp4 file.
        labels_path: the label JSON (halmstad format).
        truth_path: the npz with the true backgrounds.
        backgrounds: uint8 ``(T, H, W)`` object-free frames (before encoding).
        frames: uint8 ``(T, H, W)`` frames with the object (before encoding).
        boxes: float32 ``(T, 4)`` xywh boxes.
    """

    video_path: Path
    labels_path: Path
    truth_path: Path
    backgrounds: np.ndarray
    frames: np.ndarray
    boxes: np.ndarray


def _smooth_noise(rng: np.random.Generator, shape: tuple[int, int], sigma: float) -> np.ndarray:
    import cv2

    n = rng.standard_normal(shape).astype(np.float32)
    n = cv2.GaussianBlur(n, (0, 0), sigma)
    return n / (n.std() + 1e-6)


def make_panorama(width: int, height: int, *, rng: np.random.Generator,
                  texture: Literal["textured", "flat"] = "textured") -> np.ndarray:
    """A grayscale scene larger than the frame: sky, clouds and, when textured, a treeline.

    Args:
        width: panorama width.
        height: panorama height.
        rng: the numpy Generator every draw comes from.
        texture: ``"textured"`` (clouds + trees + buildings: features to align
            on) or ``"flat"`` (a smooth sky gradient: alignment must fail).

    Returns:
        float32 ``(height, width)`` in [0, 255].
    """
    if texture not in ("textured", "flat"):
        raise ValueError(f"texture must be 'textured' or 'flat', got {texture!r}")
    yy = np.linspace(0.0, 1.0, height, dtype=np.float32)[:, None]
    sky = 200.0 - 40.0 * (1.0 - yy) + np.zeros((height, width), np.float32)
    if texture == "flat":
        return np.clip(sky + 1.5 * _smooth_noise(rng, (height, width), 40.0), 0, 255)
    sky += 14.0 * _smooth_noise(rng, (height, width), 25.0) + 6.0 * _smooth_noise(rng, (height, width), 6.0)
    # a treeline with fine texture in the lower part, and a few buildings: corners for the matcher
    x = np.arange(width, dtype=np.float32)
    horizon = (0.58 * height + 0.05 * height * np.sin(x / 37.0) + 0.03 * height * np.sin(x / 11.0)
               + 6.0 * _smooth_noise(rng, (1, width), 3.0)[0])
    ground = (np.arange(height, dtype=np.float32)[:, None] > horizon[None, :])
    trees = 70.0 + 25.0 * _smooth_noise(rng, (height, width), 1.5) + 15.0 * _smooth_noise(rng, (height, width), 4.0)
    img = np.where(ground, trees, sky)
    for _ in range(max(3, width // 120)):
        bx = int(rng.integers(0, width - 40))
        bw, bh = int(rng.integers(15, 40)), int(rng.integers(20, 60))
        top = int(horizon[min(bx + bw // 2, width - 1)]) - bh
        img[max(top, 0):int(height), bx:bx + bw] = float(rng.uniform(90, 160))
    return np.clip(img, 0, 255).astype(np.float32)


def dark_quadcopter(index: int, rng: np.random.Generator, *, size: int = 34) -> tuple[np.ndarray, np.ndarray]:
    """Default object: a dark body with four arms and rotors, anti-aliased.

    Args:
        index: frame index (the arms turn slowly with it).
        rng: unused draws are not made; kept for the :data:`ObjectFn` signature.
        size: side of the layer in pixels.

    Returns:
        ``(layer, alpha)``, float32 ``(size, size)`` each.
    """
    import cv2

    s = 4  # supersampling for smooth edges
    big = np.zeros((size * s, size * s), np.float32)
    c = size * s / 2.0
    r = 0.42 * size * s
    ang = 0.02 * index
    for k in range(4):
        a = ang + np.pi / 4 + k * np.pi / 2
        end = (int(c + r * np.cos(a)), int(c + r * np.sin(a)))
        cv2.line(big, (int(c), int(c)), end, 1.0, thickness=max(1, int(0.08 * size * s)))
        cv2.circle(big, end, int(0.12 * size * s), 1.0, thickness=-1)
    cv2.ellipse(big, (int(c), int(c)), (int(0.2 * size * s), int(0.13 * size * s)), np.degrees(ang), 0, 360, 1.0, -1)
    alpha = cv2.resize(big, (size, size), interpolation=cv2.INTER_AREA)
    layer = np.full((size, size), 35.0, np.float32)
    return layer, np.clip(alpha, 0.0, 1.0)


def _camera(t: int, n: int, w: int, h: int, pan: float) -> np.ndarray:
    """Homography panorama -> frame at time t: translation along a curved path, small roll."""
    u = t / max(n - 1, 1)
    tx = pan * u * w + 0.04 * w * np.sin(2 * np.pi * u)
    ty = 0.5 * pan * h * (0.5 - 0.5 * np.cos(np.pi * u))
    roll = np.radians(1.0) * np.sin(2 * np.pi * u)
    cx, cy = w / 2.0, h / 2.0
    c, s = np.cos(roll), np.sin(roll)
    rot = np.array([[c, -s, cx - c * cx + s * cy], [s, c, cy - s * cx - c * cy], [0, 0, 1]])
    # small perspective term: a tilting camera is a homography, not an affinity
    persp = np.array([[1, 0, 0], [0, 1, 0], [1e-5 * np.sin(np.pi * u), 0, 1]])
    shift = np.array([[1, 0, -tx], [0, 1, -ty], [0, 0, 1]], dtype=np.float64)
    return rot @ persp @ shift


def make_panning_video(
    out_dir: str | os.PathLike,
    *,
    n_frames: int = 60,
    size: tuple[int, int] = (640, 512),
    object_fn: ObjectFn | None = None,
    seed: int = 0,
    name: str | None = None,
    class_name: str = "drone",
    texture: Literal["textured", "flat"] = "textured",
    pan: float = 0.5,
    fps: float = 30.0,
) -> SynthVideo:
    """Film a procedural panorama with a panning camera and an object on it.

    The object moves across the *frame* along a smooth loop while the camera
    pans over the scene, so, after aligning neighbouring frames, the object
    uncovers the background behind it, as in the real videos.

    Args:
        out_dir: folder receiving ``videos/``, ``labels/`` and ``truth/``.
        n_frames: T, number of frames (>= 1).
        size: ``(width, height)`` of the frames.
        object_fn: ``(frame_index, rng) -> (layer, alpha)`` (see :data:`ObjectFn`);
            default :func:`dark_quadcopter`. Plug a mesh renderer here.
        seed: seed of the numpy Generator for the scene and the object.
        name: file stem (default ``V_SYNTH_{seed:03d}``).
        class_name: class written in the label file.
        texture: ``"textured"`` or ``"flat"`` scene (see :func:`make_panorama`).
        pan: horizontal pan over the whole video, as a fraction of the frame width.
        fps: frame rate written in the video.

    Returns:
        A :class:`SynthVideo` with the paths and the truth.
    """
    import cv2

    if n_frames < 1:
        raise ValueError(f"n_frames must be >= 1, got {n_frames}")
    w, h = int(size[0]), int(size[1])
    if w < 64 or h < 64:
        raise ValueError(f"size must be at least 64x64, got {size}")
    if pan < 0:
        raise ValueError(f"pan must be >= 0, got {pan}")
    rng = np.random.default_rng(seed)
    name = name or f"V_SYNTH_{seed:03d}"
    object_fn = object_fn or dark_quadcopter
    out_dir = Path(out_dir)
    for sub in ("videos", "labels", "truth"):
        (out_dir / sub).mkdir(parents=True, exist_ok=True)
    pano_w, pano_h = int(w * (1.2 + pan)), int(h * (1.3 + 0.5 * pan))
    pano = make_panorama(pano_w, pano_h, rng=rng, texture=texture)
    offset = np.array([[1, 0, -0.1 * w], [0, 1, -0.1 * h], [0, 0, 1]], dtype=np.float64)

    backgrounds = np.empty((n_frames, h, w), np.uint8)
    frames = np.empty((n_frames, h, w), np.uint8)
    boxes = np.zeros((n_frames, 4), np.float32)
    homs = np.empty((n_frames, 3, 3), np.float64)
    video_path = out_dir / "videos" / f"{name}.mp4"
    writer = cv2.VideoWriter(str(video_path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (w, h), False)
    if not writer.isOpened():
        raise RuntimeError(f"OpenCV cannot write {video_path} (mp4v codec missing?)")
    try:
        for t in range(n_frames):
            H = _camera(t, n_frames, w, h, pan) @ offset
            homs[t] = H
            bg = cv2.warpPerspective(pano, H, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
            layer, alpha = object_fn(t, rng)
            layer = np.asarray(layer, np.float32)
            if layer.ndim == 3:
                layer = layer @ np.array([0.114, 0.587, 0.299], np.float32)  # BGR -> gray, as OpenCV
            alpha = np.clip(np.asarray(alpha, np.float32), 0.0, 1.0)
            if layer.shape != alpha.shape:
                raise ValueError(f"object_fn returned layer {layer.shape} and alpha {alpha.shape} of different sizes")
            u = t / max(n_frames - 1, 1)
            cx = w * (0.5 + 0.25 * np.sin(2 * np.pi * u + 0.3))
            cy = h * (0.35 + 0.12 * np.cos(2 * np.pi * u))
            oh, ow = alpha.shape
            x0, y0 = int(round(cx - ow / 2)), int(round(cy - oh / 2))
            comp = bg.copy()
            fx0, fy0, fx1, fy1 = max(x0, 0), max(y0, 0), min(x0 + ow, w), min(y0 + oh, h)
            if fx1 > fx0 and fy1 > fy0:
                a = alpha[fy0 - y0:fy1 - y0, fx0 - x0:fx1 - x0]
                lay = layer[fy0 - y0:fy1 - y0, fx0 - x0:fx1 - x0]
                comp[fy0:fy1, fx0:fx1] = a * lay + (1 - a) * comp[fy0:fy1, fx0:fx1]
                ys, xs = np.nonzero(a > 0.05)
                if len(xs):
                    boxes[t] = [fx0 + xs.min(), fy0 + ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1]
            backgrounds[t] = np.clip(np.rint(bg), 0, 255).astype(np.uint8)
            frames[t] = np.clip(np.rint(comp), 0, 255).astype(np.uint8)
            writer.write(frames[t])
    finally:
        writer.release()
    labels_path = out_dir / "labels" / f"{name}.json"
    label_boxes = [[round(float(v), 2) for v in b] if b[2] > 0 else None for b in boxes]
    labels_path.write_text(json.dumps({"video": video_path.name, "class": class_name,
                                       "box_format": "xywh_pixels", "boxes": label_boxes}))
    truth_path = out_dir / "truth" / f"{name}.npz"
    np.savez_compressed(truth_path, backgrounds=backgrounds, frames=frames, boxes=boxes, homographies=homs)
    return SynthVideo(video_path=video_path, labels_path=labels_path, truth_path=truth_path,
                      backgrounds=backgrounds, frames=frames, boxes=boxes)
