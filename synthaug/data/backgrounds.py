"""Background B_i of a real seed image: the same view without the object.

The paper (Sec. 4.1) obtains B_i for video seeds as the per-pixel median of
neighbouring frames once they are aligned to the seed frame, and falls back to
texture filling (inpainting) for single images. Here:

1. the object region of the seed frame is its boxes grown by a margin (labels
   are loose and motion blur spreads the object);
2. neighbouring frames (``±15, ±30, ±45, ...``, see :data:`DEFAULT_OFFSETS`) are aligned to the seed frame by
   a homography (the camera pans and tilts) estimated with OpenCV: ORB matches,
   then, on weakly textured frames, pyramidal Lucas-Kanade tracks, RANSAC in
   both cases, at reduced resolution and with the objects masked out;
3. an aligned neighbour is kept only if it agrees with the seed frame on a ring
   around the object region (a photometric check of the alignment, after a
   brightness offset); the neighbour's own object region is excluded, so the
   object can never be copied into the background;
4. inside the object region the background is the median of the kept samples
   (>= ``min_samples`` per pixel); pixels without enough samples are
   filled from their surroundings (:func:`inpaint_region`); with no usable neighbour, or for a single image,
   the whole region is inpainted;
5. outside the object region the background *is* the seed frame (no blur).

Every result records the method that served it (``"median"``,
``"median+inpaint"``, ``"inpaint"``), a quality figure (an estimate of the fill
error in gray levels: the ring residual of the aligned median, or the robust
spread of the ring for inpainting) and counts.

Example:
    >>> import numpy as np
    >>> img = np.full((64, 64), 120, np.uint8); img[20:30, 20:30] = 10
    >>> res = estimate_background_single(img, np.array([[20.0, 20.0, 10.0, 10.0]]))
    >>> res.method, int(res.background[25, 25])
    ('inpaint', 120)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from synthaug._checks import one_of

__all__ = [
    "BackgroundResult",
    "FrameAligner",
    "DEFAULT_OFFSETS",
    "object_mask",
    "grow_boxes",
    "inpaint_region",
    "estimate_background",
    "estimate_background_single",
    "estimate_backgrounds",
]

#: frame offsets tried in this order: far enough for the object to move away, near
#: enough for the alignment to hold; then in-between ones for short videos.
DEFAULT_OFFSETS: tuple[int, ...] = (-15, 15, -30, 30, -45, 45, -60, 60, -90, 90, -120, 120,
                                    -8, 8, -22, 22, -38, 38, -4, 4)


@dataclass
class BackgroundResult:
    """The estimated background of one frame.

    Attributes:
        background: uint8 ``(H, W)``, the frame with the object region filled.
        method: ``"median"``, ``"median+inpaint"``, ``"inpaint"`` or ``"none"`` (no box).
        quality: estimated fill error in gray levels (lower is better): the
            median absolute residual of the aligned median on a ring around the
            object region (median methods), or the robust spread (1.4826 MAD)
            of that ring (inpaint).
        region: bool ``(H, W)``, the pixels that were replaced.
        n_aligned: neighbours whose alignment passed the checks and were used.
        n_tried: neighbours tried.
        inpainted_fraction: fraction of ``region`` filled by inpainting.
        details: extra figures (``ring_residual``, ``object_contrast``, ``offsets_used``...).
    """

    background: np.ndarray
    method: str
    quality: float
    region: np.ndarray
    n_aligned: int = 0
    n_tried: int = 0
    inpainted_fraction: float = 0.0
    details: dict[str, Any] = field(default_factory=dict)
    background_rgb: np.ndarray | None = None  # uint8 (H, W, 3), when colour frames were given


def _inpaint_rgb(image: np.ndarray, region: np.ndarray, **kwargs: Any) -> np.ndarray:
    return np.stack([inpaint_region(np.ascontiguousarray(image[..., c]), region, **kwargs) for c in range(3)], -1)


def _as_box_array(boxes: Any) -> np.ndarray:
    if boxes is None:
        return np.zeros((0, 4), np.float64)
    arr = np.asarray(boxes, dtype=np.float64)
    if arr.size == 0:
        return np.zeros((0, 4), np.float64)
    arr = arr.reshape(-1, 4)
    if not np.all(np.isfinite(arr)) or np.any(arr[:, 2:] <= 0):
        raise ValueError(f"boxes must be finite xywh with positive size, got {arr.tolist()}")
    return arr


def grow_boxes(boxes: Any, *, margin_fraction: float = 0.25, min_margin: float = 4.0) -> np.ndarray:
    """Grow xywh boxes on every side by ``max(min_margin, margin_fraction * longest side)``.

    Example:
        >>> grow_boxes([[10, 10, 20, 10]], margin_fraction=0.25, min_margin=4).tolist()
        [[5.0, 5.0, 30.0, 20.0]]
    """
    arr = _as_box_array(boxes)
    if margin_fraction < 0 or min_margin < 0:
        raise ValueError(f"margins must be >= 0, got {margin_fraction}, {min_margin}")
    m = np.maximum(min_margin, margin_fraction * arr[:, 2:].max(axis=1, initial=0))[:, None] if len(arr) else 0
    out = arr.copy()
    if len(arr):
        out[:, :2] -= m
        out[:, 2:] += 2 * m
    return out


def object_mask(shape: tuple[int, int], boxes: Any, *, margin_fraction: float = 0.25,
                min_margin: float = 4.0) -> np.ndarray:
    """Bool ``(H, W)`` mask of the grown boxes (pixels whose centre lies in a box, rounded outwards).

    Example:
        >>> object_mask((8, 8), [[2, 2, 2, 2]], margin_fraction=0, min_margin=1).sum()
        np.int64(16)
    """
    h, w = shape
    mask = np.zeros((h, w), bool)
    for x, y, bw, bh in grow_boxes(boxes, margin_fraction=margin_fraction, min_margin=min_margin):
        x0, y0 = max(int(np.floor(x)), 0), max(int(np.floor(y)), 0)
        x1, y1 = min(int(np.ceil(x + bw)), w), min(int(np.ceil(y + bh)), h)
        if x1 > x0 and y1 > y0:
            mask[y0:y1, x0:x1] = True
    return mask


def _push_pull(img: np.ndarray, hole: np.ndarray, smooth_iters: int = 20) -> np.ndarray:
    """Smooth (membrane-like) fill of ``hole``: average known pixels down a pyramid, fill back up."""
    import cv2

    known = (~hole).astype(np.float32)
    if known.all() or not known.any() or min(img.shape) < 4:
        return img
    h, w = img.shape
    size = (max(w // 2, 1), max(h // 2, 1))
    num = cv2.resize(img * known, size, interpolation=cv2.INTER_AREA)
    den = cv2.resize(known, size, interpolation=cv2.INTER_AREA)
    small = np.where(den > 0, num / np.maximum(den, 1e-6), 0).astype(np.float32)
    small = _push_pull(small, den < 1e-3, smooth_iters)
    out = np.where(hole, cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR), img)
    for _ in range(smooth_iters):  # relax the upsampled fill towards a harmonic one
        out = np.where(hole, cv2.blur(out, (3, 3), borderType=cv2.BORDER_REPLICATE), img)
    return out


INPAINT_METHODS: tuple[str, ...] = ("pushpull", "telea", "ns")


def inpaint_region(image: np.ndarray, region: np.ndarray, *, radius: int = 5, method: str = "pushpull") -> np.ndarray:
    """Fill ``region`` of a uint8 grayscale image from its surroundings.

    ``"pushpull"`` (default) is a smooth, membrane-like fill computed with
    OpenCV resizes and blurs over a pyramid; on the large, smooth sky regions of
    aircraft videos it leaves no artefact, where OpenCV's Telea and
    Navier-Stokes inpainting (``"telea"``, ``"ns"``) draw a visible X of
    propagated isophotes. Only a window around the region is processed.

    Args:
        image: uint8 ``(H, W)``.
        region: bool ``(H, W)``, pixels to fill.
        radius: neighbourhood radius in pixels (Telea/NS; window padding).
        method: one of ``"pushpull"``, ``"telea"``, ``"ns"``.

    Returns:
        A new uint8 ``(H, W)`` image.

    Example:
        >>> img = np.tile(np.arange(0, 200, 10, dtype=np.uint8), (20, 1))  # horizontal ramp
        >>> hole = np.zeros_like(img, bool); hole[5:15, 5:15] = True
        >>> out = inpaint_region(img, hole)
        >>> int(np.abs(out.astype(int) - img).max()) <= 3
        True
    """
    import cv2

    if image.dtype != np.uint8 or image.ndim != 2:
        raise ValueError(f"image must be uint8 (H, W), got {image.dtype} {image.shape}")
    if region.shape != image.shape:
        raise ValueError(f"region shape {region.shape} differs from image shape {image.shape}")
    one_of(method, INPAINT_METHODS, "inpaint method")
    out = image.copy()
    if not region.any():
        return out
    ys, xs = np.nonzero(region)
    pad = max(3 * radius + 2, int(0.5 * max(ys.max() - ys.min(), xs.max() - xs.min())))
    y0, y1 = max(ys.min() - pad, 0), min(ys.max() + pad + 1, image.shape[0])
    x0, x1 = max(xs.min() - pad, 0), min(xs.max() + pad + 1, image.shape[1])
    win_img = np.ascontiguousarray(image[y0:y1, x0:x1])
    win_reg = region[y0:y1, x0:x1]
    if method == "pushpull":
        win = np.clip(np.rint(_push_pull(win_img.astype(np.float32), win_reg)), 0, 255).astype(np.uint8)
    else:
        flag = cv2.INPAINT_TELEA if method == "telea" else cv2.INPAINT_NS
        win = cv2.inpaint(win_img, win_reg.astype(np.uint8), radius, flag)
    out[y0:y1, x0:x1][win_reg] = win[win_reg]
    return out


def _ring(region: np.ndarray, width: int) -> np.ndarray:
    import cv2

    k = 2 * width + 1
    grown = cv2.dilate(region.astype(np.uint8), np.ones((k, k), np.uint8)) > 0
    return grown & ~region


def _robust_spread(values: np.ndarray) -> float:
    if values.size == 0:
        return float("nan")
    return float(1.4826 * np.median(np.abs(values - np.median(values))))


class FrameAligner:
    """Homographies between frames of one video, features cached per frame.

    Args:
        frames: uint8 ``(T, H, W)`` grayscale frames.
        boxes: per frame ``None`` or xywh box(es); these (grown) regions are
            excluded from feature detection, so the moving object does not
            vote for the camera motion.
        scale: resolution factor at which features are found (0.5: half size).
        min_inliers: RANSAC inliers needed to accept a homography.
        max_features: ORB features per frame.

    Example:
        >>> import numpy as np
        >>> rng = np.random.default_rng(0)
        >>> import cv2
        >>> base = cv2.GaussianBlur((rng.random((240, 320)) * 255).astype(np.uint8), (0, 0), 3)
        >>> base = cv2.normalize(base, None, 0, 255, cv2.NORM_MINMAX)
        >>> shifted = np.roll(base, (3, 7), axis=(0, 1))
        >>> H = FrameAligner(np.stack([base, shifted]), [None, None]).homography(0, 1)
        >>> bool(np.allclose(H, [[1, 0, 7], [0, 1, 3], [0, 0, 1]], atol=0.15))
        True
    """

    def __init__(self, frames: np.ndarray, boxes: Sequence[Any], *, scale: float = 0.5, min_inliers: int = 15,
                 max_features: int = 1000) -> None:
        if frames.ndim != 3 or frames.dtype != np.uint8:
            raise ValueError(f"frames must be uint8 (T, H, W), got {frames.dtype} {frames.shape}")
        if len(boxes) != len(frames):
            raise ValueError(f"need one box entry per frame, got {len(boxes)} for {len(frames)} frames")
        if not 0 < scale <= 1:
            raise ValueError(f"scale must be in (0, 1], got {scale}")
        self.frames, self.boxes, self.scale = frames, boxes, scale
        self.min_inliers, self.max_features = min_inliers, max_features
        self._small: dict[int, np.ndarray] = {}
        self._feat: dict[int, tuple[Any, Any]] = {}
        self._masks: dict[int, np.ndarray] = {}
        self._corners: dict[int, Any] = {}

    def small(self, i: int) -> np.ndarray:
        import cv2

        if i not in self._small:
            f = self.frames[i]
            if self.scale < 1:
                f = cv2.resize(f, None, fx=self.scale, fy=self.scale, interpolation=cv2.INTER_AREA)
            self._small[i] = f
        return self._small[i]

    def feature_mask(self, i: int) -> np.ndarray:
        if i not in self._masks:
            small = self.small(i)
            b = _as_box_array(self.boxes[i]) * self.scale
            self._masks[i] = (~object_mask(small.shape, b, margin_fraction=0.5, min_margin=4)).astype(np.uint8) * 255
        return self._masks[i]

    def _features(self, i: int) -> tuple[Any, Any]:
        import cv2

        if i not in self._feat:
            orb = cv2.ORB_create(nfeatures=self.max_features, fastThreshold=7)
            self._feat[i] = orb.detectAndCompute(self.small(i), self.feature_mask(i))
        return self._feat[i]

    def _ransac(self, src: np.ndarray, dst: np.ndarray) -> np.ndarray | None:
        import cv2

        if len(src) < self.min_inliers:
            return None
        H, inl = cv2.findHomography(src, dst, cv2.RANSAC, 1.5, maxIters=2000, confidence=0.995)
        if H is None or inl is None or int(inl.sum()) < self.min_inliers or inl.mean() < 0.3:
            return None
        return H

    def _orb(self, src: int, dst: int) -> np.ndarray | None:
        import cv2

        ks, ds = self._features(src)
        kd, dd = self._features(dst)
        if ds is None or dd is None or len(ks) < self.min_inliers or len(kd) < self.min_inliers:
            return None
        matches = cv2.BFMatcher(cv2.NORM_HAMMING).knnMatch(ds, dd, k=2)
        good = [m[0] for m in matches if len(m) == 2 and m[0].distance < 0.8 * m[1].distance]
        if len(good) < self.min_inliers:
            return None
        ps = np.float32([ks[m.queryIdx].pt for m in good])
        pd = np.float32([kd[m.trainIdx].pt for m in good])
        return self._ransac(ps, pd)

    def _lk(self, src: int, dst: int, guess: np.ndarray | None = None) -> np.ndarray | None:
        """Track corners of ``src`` into ``dst`` (from ``guess``'s prediction when given), then RANSAC."""
        import cv2

        a, b = self.small(src), self.small(dst)
        if src not in self._corners:
            self._corners[src] = cv2.goodFeaturesToTrack(a, maxCorners=400, qualityLevel=0.005, minDistance=6,
                                                         mask=self.feature_mask(src))
        pts = self._corners[src]
        if pts is None or len(pts) < self.min_inliers:
            return None
        params = dict(winSize=(21, 21), maxLevel=2 if guess is not None else 4,
                      criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01))
        if guess is not None:
            pred = cv2.perspectiveTransform(pts, guess).astype(np.float32)
            fwd, st1, _ = cv2.calcOpticalFlowPyrLK(a, b, pts, pred.copy(), flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **params)
        else:
            fwd, st1, _ = cv2.calcOpticalFlowPyrLK(a, b, pts, None, **params)
        back, st2, _ = cv2.calcOpticalFlowPyrLK(b, a, fwd, pts.copy(), flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **params)
        ok = (st1[:, 0] == 1) & (st2[:, 0] == 1) & (np.linalg.norm((back - pts)[:, 0], axis=1) < 0.5)
        return self._ransac(pts[ok, 0], fwd[ok, 0])

    def homography(self, src: int, dst: int) -> np.ndarray | None:
        """Full-resolution homography mapping pixels of frame ``src`` onto frame ``dst``, or None.

        ``None`` when neither ORB matching nor LK tracking yields a plausible
        homography (too few inliers, or a warp far from a camera rotation:
        strong scaling, shear or perspective).
        """
        # ORB matching copes with large pans; LK tracking, started from the ORB
        # estimate, makes it sub-pixel, and alone it copes with weak texture.
        H = self._orb(src, dst)
        H = self._lk(src, dst, H) if H is not None else self._lk(src, dst)
        if H is None:
            return None
        s = self.scale
        S = np.diag([s, s, 1.0])
        H = np.linalg.inv(S) @ H @ S
        H /= H[2, 2]
        det = np.linalg.det(H[:2, :2])
        if not (0.8 < det < 1.25) or np.abs(H[2, :2]).max() > 1e-3:
            return None
        return H


def _box_list(boxes: Any) -> np.ndarray:
    return _as_box_array(boxes)


def estimate_background(
    frames: np.ndarray,
    boxes: Sequence[Any],
    index: int,
    *,
    offsets: Sequence[int] = DEFAULT_OFFSETS,
    aligner: FrameAligner | None = None,
    min_samples: int = 2,
    max_neighbours: int = 10,
    margin_fraction: float = 0.25,
    min_margin: float = 4.0,
    max_residual: float = 8.0,
    max_inpainted_fraction: float = 0.9,
    inpaint_radius: int = 5,
    inpaint_method: str = "pushpull",
    colour_frames: np.ndarray | None = None,
) -> BackgroundResult:
    """Background of ``frames[index]``: aligned median of neighbours, inpainting where that fails.

    Args:
        frames: uint8 ``(T, H, W)`` grayscale frames of one video.
        boxes: per frame ``None`` (object not visible / unknown) or xywh box(es).
            Neighbours without a box are not used (the object could be anywhere).
        index: the seed frame.
        offsets: neighbour offsets to try, in order of preference.
        aligner: a :class:`FrameAligner` for these frames (shares the feature
            cache between seeds of one video); built when None.
        min_samples: aligned samples a pixel needs for the median.
        max_neighbours: stop after this many usable neighbours (otherwise
            neighbours are tried until every object pixel has ``min_samples``
            samples or ``offsets`` is exhausted).
        margin_fraction: object region = box grown by this fraction of its
            longest side (at least ``min_margin`` pixels) on each side.
        min_margin: see ``margin_fraction``.
        max_residual: a neighbour whose aligned ring residual (median absolute
            difference, gray levels) exceeds this is rejected.
        max_inpainted_fraction: when more of the object region than this lacks
            ``min_samples`` aligned samples, the whole region is inpainted
            instead of mixing a few median pixels into a large inpainted hole.
        inpaint_radius: radius of the Telea inpainting.
        inpaint_method: see :func:`inpaint_region`.
        colour_frames: the same frames in RGB ``(T, H, W, 3)``: the colour background is
            made alongside (same neighbours, homographies, masks and fill; each channel's
            own brightness offset), in ``background_rgb``.

    Returns:
        A :class:`BackgroundResult`.

    Shape:
        frames ``(T, H, W)`` uint8 -> background ``(H, W)`` uint8.
    """
    if frames.ndim != 3 or frames.dtype != np.uint8:
        raise ValueError(f"frames must be uint8 (T, H, W), got {frames.dtype} {frames.shape}")
    if len(boxes) != len(frames):
        raise ValueError(f"need one box entry per frame, got {len(boxes)} for {len(frames)} frames")
    if not 0 <= index < len(frames):
        raise ValueError(f"index must be in [0, {len(frames)}), got {index}")
    if min_samples < 1:
        raise ValueError(f"min_samples must be >= 1, got {min_samples}")
    target = frames[index]
    h, w = target.shape
    if colour_frames is not None and (colour_frames.shape != frames.shape + (3,) or colour_frames.dtype != np.uint8):
        raise ValueError(f"colour_frames must be uint8 {frames.shape + (3,)}, got {colour_frames.dtype} "
                         f"{colour_frames.shape}")
    target_rgb = None if colour_frames is None else colour_frames[index]
    tboxes = _box_list(boxes[index])
    if len(tboxes) == 0:
        return BackgroundResult(target.copy(), "none", 0.0, np.zeros((h, w), bool),
                                background_rgb=None if target_rgb is None else target_rgb.copy())
    win = _object_window((h, w), tboxes, margin_fraction=margin_fraction, min_margin=min_margin)
    region = win.region
    aligner = aligner if aligner is not None else FrameAligner(frames, boxes)
    nb = _aligned_neighbours(frames, boxes, index, offsets, aligner, win, colour_frames=colour_frames,
                             min_samples=min_samples, max_neighbours=max_neighbours, margin_fraction=margin_fraction,
                             min_margin=min_margin, max_residual=max_residual)

    ring_vals = win.crop(target).astype(np.float32)[win.ring_roi]
    details: dict[str, Any] = {"offsets_used": nb.used, "neighbour_residuals": [round(r, 3) for r in nb.residuals],
                               "ring_spread": round(_robust_spread(ring_vals), 3)}
    method, fill, fill_rgb, inpainted_fraction = "inpaint", None, None, 1.0
    quality = _robust_spread(ring_vals)
    if nb.samples:
        median = _median_fill(target, target_rgb, win, nb, min_samples=min_samples,
                              max_inpainted_fraction=max_inpainted_fraction, inpaint_radius=inpaint_radius,
                              inpaint_method=inpaint_method)
        if median is not None:
            # No leak test against the inpainted fill is made here: it fires on textured
            # scenes where inpainting is the worse estimate. The object cannot leak
            # because every neighbour's own (grown) object region is excluded, and a
            # mislabelled neighbour is outvoted by the median of >= min_samples samples.
            fill, fill_rgb, holes, ring_resid = median
            details["ring_residual"] = round(ring_resid, 3)
            inpainted_fraction = float(holes.sum() / max(region.sum(), 1))
            method = "median" if not holes.any() else "median+inpaint"
            quality = ring_resid
    background = fill if fill is not None else inpaint_region(target, region, radius=inpaint_radius, method=inpaint_method)
    background_rgb = None
    if target_rgb is not None:
        background_rgb = fill_rgb if fill is not None else _inpaint_rgb(target_rgb, region, radius=inpaint_radius,
                                                                         method=inpaint_method)
    in_box = object_mask((h, w), tboxes, margin_fraction=0, min_margin=0)
    details["object_contrast"] = round(float(np.mean(np.abs(background[in_box].astype(np.float32) - target[in_box]))), 3)
    return BackgroundResult(background=background, method=method, quality=float(quality), region=region,
                            n_aligned=len(nb.samples) if method != "inpaint" else 0, n_tried=nb.tried,
                            inpainted_fraction=float(inpainted_fraction), details=details,
                            background_rgb=background_rgb)


@dataclass
class _ObjectWindow:
    """A seed's object region (its grown boxes), the ring of background around it, and the window
    ``[y0:y1, x0:x1]`` holding both (where neighbours are warped to)."""

    region: np.ndarray
    ring: np.ndarray
    y0: Any
    y1: Any
    x0: Any
    x1: Any

    @property
    def size(self) -> tuple[Any, Any]:
        """``(width, height)`` of the window (OpenCV's ``dsize``)."""
        return (self.x1 - self.x0, self.y1 - self.y0)

    @property
    def reg_roi(self) -> np.ndarray:
        return self.region[self.y0:self.y1, self.x0:self.x1]

    @property
    def ring_roi(self) -> np.ndarray:
        return self.ring[self.y0:self.y1, self.x0:self.x1]

    def crop(self, image: np.ndarray) -> np.ndarray:
        return image[self.y0:self.y1, self.x0:self.x1]

    def shift(self) -> np.ndarray:
        """Frame pixels -> window pixels (a homography)."""
        return np.array([[1, 0, -self.x0], [0, 1, -self.y0], [0, 0, 1]], dtype=np.float64)


def _object_window(shape: tuple[int, int], tboxes: np.ndarray, *, margin_fraction: float,
                   min_margin: float) -> _ObjectWindow:
    region = object_mask(shape, tboxes, margin_fraction=margin_fraction, min_margin=min_margin)
    ring_w = int(max(6, min_margin, margin_fraction * tboxes[:, 2:].max()))
    ring = _ring(region, ring_w)
    ys, xs = np.nonzero(region | ring)
    return _ObjectWindow(region, ring, ys.min(), ys.max() + 1, xs.min(), xs.max() + 1)


@dataclass
class _Neighbours:
    """The aligned neighbours of a seed frame: window samples (brightness-matched, NaN where unknown)."""

    samples: list[np.ndarray] = field(default_factory=list)
    samples_rgb: list[np.ndarray] = field(default_factory=list)
    used: list[int] = field(default_factory=list)
    residuals: list[float] = field(default_factory=list)
    tried: int = 0


def _aligned_neighbours(frames: np.ndarray, boxes: Sequence[Any], index: int, offsets: Sequence[int],
                        aligner: FrameAligner, win: _ObjectWindow, *, colour_frames: np.ndarray | None,
                        min_samples: int, max_neighbours: int, margin_fraction: float, min_margin: float,
                        max_residual: float) -> _Neighbours:
    """Neighbours at ``offsets`` (with a box) aligned onto the seed's window, until every object pixel has
    ``min_samples`` samples or ``max_neighbours`` were used (see :func:`estimate_background`)."""
    nb = _Neighbours()
    reg_roi = win.reg_roi
    for off in offsets:
        j = index + int(off)
        if not 0 <= j < len(frames) or j == index or len(_box_list(boxes[j])) == 0:
            continue
        nb.tried += 1
        H = aligner.homography(j, index)
        if H is None:
            continue
        sample = _neighbour_sample(frames, boxes, j, index, win.shift() @ H, win, colour_frames=colour_frames,
                                   margin_fraction=margin_fraction, min_margin=min_margin, max_residual=max_residual)
        if sample is None:
            continue
        gray, rgb, resid = sample
        nb.samples.append(gray)
        if rgb is not None:
            nb.samples_rgb.append(rgb)
        nb.used.append(int(off))
        nb.residuals.append(resid)
        if len(nb.samples) >= max_neighbours:
            break
        if len(nb.samples) >= min_samples:
            counts = np.isfinite(np.stack(nb.samples))[:, reg_roi].sum(axis=0)
            if counts.min() >= min_samples:
                break
    return nb


def _neighbour_sample(frames: np.ndarray, boxes: Sequence[Any], j: int, index: int, M: np.ndarray,
                      win: _ObjectWindow, *, colour_frames: np.ndarray | None, margin_fraction: float,
                      min_margin: float, max_residual: float) -> tuple[np.ndarray, np.ndarray | None, float] | None:
    """Frame ``j`` warped by ``M`` onto the window, its own object region masked (NaN), brightness-matched
    to the seed on the ring: ``(gray, rgb or None, ring residual)``; None when the ring is mostly unseen
    or the residual exceeds ``max_residual``."""
    import cv2

    h, w = frames.shape[1:]
    ring_roi = win.ring_roi
    tgt_roi = win.crop(frames[index]).astype(np.float32)
    warped = cv2.warpPerspective(frames[j].astype(np.float32), M, win.size, flags=cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_CONSTANT, borderValue=float("nan"))
    nmask = object_mask((h, w), _box_list(boxes[j]), margin_fraction=margin_fraction,
                        min_margin=min_margin).astype(np.uint8)
    nmask_w = cv2.warpPerspective(nmask, M, win.size, flags=cv2.INTER_NEAREST,
                                  borderMode=cv2.BORDER_CONSTANT, borderValue=1) > 0
    warped[nmask_w] = np.nan
    ring_ok = ring_roi & np.isfinite(warped)
    if ring_ok.sum() < 0.5 * ring_roi.sum():
        return None
    diff = tgt_roi[ring_ok] - warped[ring_ok]
    offset = float(np.median(diff))
    resid = float(np.median(np.abs(diff - offset)))
    if resid > max_residual:
        return None
    rgb = None
    if colour_frames is not None:
        wc = cv2.warpPerspective(colour_frames[j].astype(np.float32), M, win.size, flags=cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_CONSTANT, borderValue=(float("nan"),) * 3)
        wc[~np.isfinite(warped)] = np.nan
        t_rgb = win.crop(colour_frames[index]).astype(np.float32)
        rgb = wc + np.median(t_rgb[ring_ok] - wc[ring_ok], axis=0)  # each channel's offset
    return warped + offset, rgb, resid


def _median_fill(target: np.ndarray, target_rgb: np.ndarray | None, win: _ObjectWindow, nb: _Neighbours, *,
                 min_samples: int, max_inpainted_fraction: float, inpaint_radius: int,
                 inpaint_method: str) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, float] | None:
    """The seed frame with its object region replaced by the neighbours' median where ``min_samples`` agree,
    inpainted elsewhere: ``(gray, rgb or None, holes inpainted, ring residual)``; None when more than
    ``max_inpainted_fraction`` of the region lacks samples."""
    h, w = target.shape
    reg_roi, ring_roi = win.reg_roi, win.ring_roi
    tgt_roi = win.crop(target).astype(np.float32)
    stack = np.stack(nb.samples)
    finite = np.isfinite(stack)
    counts = finite.sum(axis=0)
    with np.errstate(all="ignore"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            med = np.nanmedian(stack, axis=0)
    enough = (counts >= min_samples) & reg_roi
    frac_missing = 1.0 - enough.sum() / max(reg_roi.sum(), 1)
    if frac_missing > max_inpainted_fraction:
        return None
    ring_med = ring_roi & (counts >= 1)
    ring_resid = (float(np.median(np.abs(tgt_roi[ring_med] - med[ring_med]))) if ring_med.any()
                  else _robust_spread(tgt_roi[ring_roi]))
    composite = target.copy()
    roi = win.crop(composite)
    roi[enough] = np.clip(np.rint(med[enough]), 0, 255).astype(np.uint8)
    holes = np.zeros((h, w), bool)
    holes[win.y0:win.y1, win.x0:win.x1] = reg_roi & ~enough
    if holes.any():
        composite = inpaint_region(composite, holes, radius=inpaint_radius, method=inpaint_method)
    fill_rgb = None
    if target_rgb is not None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            med_rgb = np.nanmedian(np.stack(nb.samples_rgb), axis=0)
        fill_rgb = target_rgb.copy()
        win.crop(fill_rgb)[enough] = np.clip(np.rint(med_rgb[enough]), 0, 255).astype(np.uint8)
        if holes.any():
            fill_rgb = _inpaint_rgb(fill_rgb, holes, radius=inpaint_radius, method=inpaint_method)
    return composite, fill_rgb, holes, ring_resid


def estimate_background_single(image: np.ndarray, boxes: Any, *, margin_fraction: float = 0.25,
                               min_margin: float = 4.0, inpaint_radius: int = 5,
                               inpaint_method: str = "pushpull") -> BackgroundResult:
    """Background of a single image (no neighbours): texture filling of every grown box.

    Args:
        image: uint8 ``(H, W)``.
        boxes: xywh box(es) of all objects in the image.
        margin_fraction: see :func:`estimate_background`.
        min_margin: see :func:`estimate_background`.
        inpaint_radius: radius of the Telea inpainting.
        inpaint_method: see :func:`inpaint_region`.

    Returns:
        A :class:`BackgroundResult` with method ``"inpaint"`` (``"none"`` without boxes).
    """
    if image.ndim != 2 or image.dtype != np.uint8:
        raise ValueError(f"image must be uint8 (H, W), got {image.dtype} {image.shape}")
    return estimate_background(image[None], [boxes], 0, offsets=(), margin_fraction=margin_fraction,
                               min_margin=min_margin, inpaint_radius=inpaint_radius, inpaint_method=inpaint_method)


def estimate_backgrounds(frames: np.ndarray, boxes: Sequence[Any], indices: Sequence[int],
                         **kwargs: Any) -> list[BackgroundResult]:
    """:func:`estimate_background` for several seed frames of one video, sharing one aligner."""
    aligner = kwargs.pop("aligner", None) or FrameAligner(frames, boxes)
    return [estimate_background(frames, boxes, int(i), aligner=aligner, **kwargs) for i in indices]
