"""Levi & Weiss (2004) edge-orientation-histogram weak learners, batched in torch.

The paper's AdaBoost detector and its distances ``wl_random`` / ``wl_learned``
(Rozantsev et al., eq. 4-5) use weak learners

    h_{R,o,τ}(X) = 1  if  E(X, R, o) > τ  else 0,

where E(X, R, o) is the *normalised gradient energy* of image X over the
rectangle R in orientation bin o (Levi & Weiss, "Learning object detection
from a small number of examples: the importance of good features", CVPR 2004):

    E(X, R, o) = G_o(R) / (Σ_k G_k(R) + ε),

G_k(R) the sum over R of the gradient magnitude of the pixels whose (unsigned)
gradient orientation falls in bin k. The sums come from one integral image per
bin, so any rectangle costs four look-ups.

An optional energy *floor* per pixel (``floor``, the AdaBoost detector's
``ada_energy_floor``) adds ``floor · |R|`` to the denominator: the paper's E is
contrast-invariant, so a rectangle of faint, smooth structure shows its
orientations at the strength of a sharp edge; with the floor it scores low in
every bin. The distances keep the paper's E (floor 0).

Definitions used here (the numpy reference in ``tests/test_weak_learners.py``
implements them independently):
    - gradient: central differences ``g_x = (X[y, x+1] - X[y, x-1]) / 2``,
      ``g_y`` likewise, with edge replication at the image border;
    - magnitude ``sqrt(g_x² + g_y² + 1e-12)`` (the tiny term keeps the gradient
      of the magnitude finite on flat areas);
    - orientation ``θ = atan2(g_y, g_x) mod π`` quantised to the nearest of
      ``n_bins`` bin centres ``k π / n_bins`` (bin 0 = horizontal gradient,
      i.e. vertical edges);
    - rectangles ``(y0, x0, h, w)`` in window coordinates, always inside the
      window's interior ``[1, window - 1)``: there the central differences only
      read pixels of the window, so a weak learner gives the same value on a
      cropped patch as on the same window of a full frame.

Example:
    >>> import torch
    >>> g = torch.Generator().manual_seed(0)
    >>> rects, orients = random_candidates(5, window=40, n_bins=4, generator=g)
    >>> x = torch.rand(3, 1, 40, 40, generator=g)
    >>> e = edge_orientation_energy(x, rects, orients, n_bins=4)
    >>> e.shape, bool(((e >= 0) & (e <= 1)).all())
    (torch.Size([3, 5]), True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import torch
from torch import Tensor

__all__ = [
    "DEFAULT_EPS",
    "WeakLearners",
    "orientation_maps",
    "interior_orientation_maps",
    "interior_block_integrals",
    "orientation_integrals",
    "rect_sums",
    "edge_orientation_energy",
    "random_candidates",
    "exhaustive_candidates",
    "weak_learner_response",
]

DEFAULT_EPS = 1e-3
"""ε of E(X, R, o): keeps flat rectangles at E ≈ 0 instead of 0/0."""

_MAG_EPS = 1e-12


def _check_batch(x: Tensor) -> Tensor:
    if not isinstance(x, Tensor):
        raise ValueError(f"x must be a torch.Tensor, got {type(x).__name__}")
    if x.dim() == 3:
        x = x[:, None]
    if x.dim() != 4 or x.shape[1] != 1:
        raise ValueError(f"x must be (B, 1, H, W) grayscale, got shape {tuple(x.shape)}")
    if not x.dtype.is_floating_point:
        raise ValueError(f"x must be a float tensor, got dtype {x.dtype}")
    return x


def _check_n_bins(n_bins: int) -> int:
    if not isinstance(n_bins, int) or n_bins < 2:
        raise ValueError(f"n_bins must be an int >= 2, got {n_bins}")
    return n_bins


def orientation_maps(x: Tensor, n_bins: int = 4) -> Tensor:
    """Gradient magnitude split into ``n_bins`` unsigned orientation channels.

    Args:
        x: grayscale images.
        n_bins: number of orientation bins K over [0, π).

    Returns:
        ``out[:, k]`` = gradient magnitude where the orientation is in bin k, 0 elsewhere.

    Shape:
        - x: (B, 1, H, W)
        - output: (B, K, H, W)

    Example:
        >>> x = torch.zeros(1, 1, 5, 5); x[..., 3:] = 1.0   # a vertical edge
        >>> m = orientation_maps(x, n_bins=4)
        >>> m[0, :, 2, 2].tolist()   # horizontal gradient -> bin 0
        [0.5, 0.0, 0.0, 0.0]
    """
    x = _check_batch(x)
    n_bins = _check_n_bins(n_bins)
    p = torch.nn.functional.pad(x, (1, 1, 1, 1), mode="replicate")
    return _binned_magnitude(p, n_bins)


def interior_orientation_maps(x: Tensor, n_bins: int = 4) -> Tensor:
    """:func:`orientation_maps` of the interior pixels only (no padding needed).

    ``out[..., i, j] == orientation_maps(x)[..., i + 1, j + 1]``: the one-pixel
    border ring, where the central difference would need a pixel outside the
    image, is left out. Weak-learner rectangles never touch a window's border
    ring, so sliding-window scoring only needs these values.

    Shape:
        - x: (B, 1, H, W)
        - output: (B, K, H - 2, W - 2)

    Example:
        >>> x = torch.rand(2, 1, 9, 7)
        >>> torch.equal(interior_orientation_maps(x), orientation_maps(x)[..., 1:-1, 1:-1])
        True
    """
    x = _check_batch(x)
    return _binned_magnitude(x, _check_n_bins(n_bins))


def _magnitude_and_bin(p: Tensor, n_bins: int) -> tuple[Tensor, Tensor]:
    """Central-difference gradient magnitude of the interior of ``p`` and its orientation bin (a float index).

    Shape:
        - p: (B, 1, H, W)
        - output: (B, 1, H - 2, W - 2) twice
    """
    gx = (p[..., 1:-1, 2:] - p[..., 1:-1, :-2]) * 0.5
    gy = (p[..., 2:, 1:-1] - p[..., :-2, 1:-1]) * 0.5
    mag = torch.sqrt(gx * gx + gy * gy + _MAG_EPS)
    with torch.no_grad():
        # round(θ K / π) mod K with θ = atan2 mod π; as selects rather than float remainders
        # (equal bins, ~10x cheaper): θ < 0 moves up by π, and q = K (θ near π) wraps to 0
        theta = torch.atan2(gy, gx)
        theta = torch.where(theta < 0, theta + math.pi, theta)
        bins = torch.round(theta * (n_bins / math.pi))
        bins = torch.where(bins >= n_bins, bins - n_bins, bins)
    return mag, bins


def _binned_magnitude(p: Tensor, n_bins: int) -> Tensor:
    """Central-difference gradients of the interior of ``p``, magnitude split by orientation bin."""
    mag, bins = _magnitude_and_bin(p, n_bins)
    with torch.no_grad():
        centres = torch.arange(n_bins, dtype=bins.dtype, device=bins.device).view(1, -1, 1, 1)
        in_bin = bins == centres  # (B, K, h, w)
    return torch.where(in_bin, mag, torch.zeros((), dtype=mag.dtype, device=mag.device))


def interior_block_integrals(x: Tensor, n_bins: int = 4, block: int = 1) -> Tensor:
    """Float64 integral images of :func:`interior_orientation_maps` summed over ``block x block`` blocks.

    Block ``(i, j)`` covers the interior pixels ``[i*block, (i+1)*block) x [j*block, (j+1)*block)``
    (image pixels shifted by one); incomplete blocks at the bottom and right are left out.
    The block sums are one scatter-add of the magnitudes into bin planes (no
    ``(K, H, W)`` one-hot map); the last plane is the sum of the bin planes'
    integrals (all orientations). Equal to cumulative sums of
    ``interior_orientation_maps(x)`` converted to float64 and block-summed: the
    float32 magnitudes lie in [1e-6, 1], so their sums of up to 2^20 terms
    are exact in float64 whatever the order.

    Shape:
        - x: (1, 1, H, W)
        - output: (K + 1, (H - 2) // block + 1, (W - 2) // block + 1), zero first row and column

    Example:
        >>> x = torch.rand(1, 1, 18, 22)
        >>> ii = interior_block_integrals(x, 4, block=4)
        >>> m = interior_orientation_maps(x, 4)[0, :, :16, :20].double().reshape(4, 4, 4, 5, 4).sum((2, 4))
        >>> torch.allclose(ii[:4, 1:, 1:], m.cumsum(-1).cumsum(-2)), tuple(ii.shape)
        (True, (5, 5, 6))
    """
    x = _check_batch(x)
    n_bins = _check_n_bins(n_bins)
    if x.shape[0] != 1:
        raise ValueError(f"x must hold one image (1, 1, H, W), got shape {tuple(x.shape)}")
    if not isinstance(block, int) or block < 1:
        raise ValueError(f"block must be an int >= 1, got {block}")
    mag, bins = _magnitude_and_bin(x, n_bins)
    nbh, nbw = mag.shape[-2] // block, mag.shape[-1] // block
    mag, bins = mag[0, 0, : nbh * block, : nbw * block], bins[0, 0, : nbh * block, : nbw * block]
    rows = (torch.arange(nbh * block, device=x.device) // block) * nbw
    cols = torch.arange(nbw * block, device=x.device) // block
    index = bins.long() * (nbh * nbw) + rows[:, None] + cols[None, :]
    sums = torch.zeros(n_bins * nbh * nbw, dtype=torch.float64, device=x.device)
    sums.index_add_(0, index.reshape(-1), mag.reshape(-1).double())
    ii = torch.nn.functional.pad(sums.view(n_bins, nbh, nbw).cumsum(-1).cumsum(-2), (1, 0, 1, 0))
    return torch.cat([ii, ii.sum(0, keepdim=True)])


def orientation_integrals(x: Tensor, n_bins: int = 4, dtype: torch.dtype | None = None) -> Tensor:
    """Integral images of :func:`orientation_maps`, with a leading zero row and column.

    ``I[b, k, y, x] = Σ_{y' < y, x' < x} M[b, k, y', x']``, so the sum over rows
    ``y0..y0+h-1`` and columns ``x0..x0+w-1`` is
    ``I[y0+h, x0+w] - I[y0, x0+w] - I[y0+h, x0] + I[y0, x0]``.

    Args:
        x: grayscale images.
        n_bins: number of orientation bins K.
        dtype: accumulation dtype (``torch.float64`` keeps full frames exact);
            the input dtype when None.

    Shape:
        - x: (B, 1, H, W)
        - output: (B, K, H + 1, W + 1)

    Example:
        >>> ii = orientation_integrals(torch.rand(2, 1, 8, 9), n_bins=4)
        >>> ii.shape
        torch.Size([2, 4, 9, 10])
    """
    m = orientation_maps(x, n_bins)
    if dtype is not None:
        m = m.to(dtype)
    ii = m.cumsum(-1).cumsum(-2)
    return torch.nn.functional.pad(ii, (1, 0, 1, 0))


def _check_rects(rects: Tensor) -> Tensor:
    if not isinstance(rects, Tensor) or rects.dim() != 2 or rects.shape[1] != 4:
        shape = tuple(rects.shape) if isinstance(rects, Tensor) else type(rects).__name__
        raise ValueError(f"rects must be an (R, 4) tensor of (y0, x0, h, w), got {shape}")
    rects = rects.long()
    if rects.numel() and (rects[:, :2].min() < 0 or rects[:, 2:].min() < 1):
        raise ValueError(f"rects need y0, x0 >= 0 and h, w >= 1, got min {rects.min(0).values.tolist()}")
    return rects


def rect_sums(integrals: Tensor, rects: Tensor) -> Tensor:
    """Sum of every channel over every rectangle, by four integral-image look-ups.

    Args:
        integrals: output of :func:`orientation_integrals` (or any ``(B, C, H+1, W+1)``
            integral image with a zero first row/column).
        rects: rectangles ``(y0, x0, h, w)``, all inside the image.

    Returns:
        ``out[b, c, r]`` = sum of channel c over rectangle r.

    Shape:
        - integrals: (B, C, H + 1, W + 1)
        - rects: (R, 4)
        - output: (B, C, R)

    Example:
        >>> m = torch.arange(12.).reshape(1, 1, 3, 4)
        >>> ii = torch.nn.functional.pad(m.cumsum(-1).cumsum(-2), (1, 0, 1, 0))
        >>> rect_sums(ii, torch.tensor([[1, 1, 2, 2]])).item() == m[0, 0, 1:3, 1:3].sum().item()
        True
    """
    rects = _check_rects(rects)
    h1, w1 = integrals.shape[-2:]
    if rects.numel() and (int((rects[:, 0] + rects[:, 2]).max()) > h1 - 1 or int((rects[:, 1] + rects[:, 3]).max()) > w1 - 1):
        raise ValueError(f"a rectangle exceeds the {h1 - 1}x{w1 - 1} image: max y1 "
                         f"{int((rects[:, 0] + rects[:, 2]).max())}, max x1 {int((rects[:, 1] + rects[:, 3]).max())}")
    y0, x0 = rects[:, 0], rects[:, 1]
    y1, x1 = y0 + rects[:, 2], x0 + rects[:, 3]
    return integrals[..., y1, x1] - integrals[..., y0, x1] - integrals[..., y1, x0] + integrals[..., y0, x0]


def edge_orientation_energy(
    x: Tensor,
    rects: Tensor,
    orientations: Tensor,
    n_bins: int = 4,
    eps: float = DEFAULT_EPS,
    floor: float = 0.0,
) -> Tensor:
    """E(X, R, o): normalised gradient energy of each image over each (rectangle, bin) pair.

    Args:
        x: grayscale images.
        rects: rectangles ``(y0, x0, h, w)`` inside the images.
        orientations: one bin index per rectangle, in ``[0, n_bins)``.
        n_bins: number of orientation bins K.
        eps: ε of the normalisation ``G_o / (Σ_k G_k + ε)``.
        floor: an energy floor per pixel: the normalisation becomes ``G_o / (Σ_k G_k + ε + floor · |R|)``
            (|R| the rectangle's area), so a rectangle whose gradients are at or below the floor's level scores
            low in every bin instead of showing its faint structure at full strength (0: the paper's E).

    Returns:
        Energies in [0, 1).

    Shape:
        - x: (B, 1, H, W)
        - rects: (M, 4)
        - orientations: (M,)
        - output: (B, M)
    """
    if eps < 0 or not math.isfinite(eps):
        raise ValueError(f"eps must be finite and >= 0, got {eps}")
    if not (floor >= 0 and math.isfinite(floor)):
        raise ValueError(f"floor must be finite and >= 0, got {floor}")
    orientations = torch.as_tensor(orientations).long()
    if orientations.dim() != 1 or orientations.shape[0] != rects.shape[0]:
        raise ValueError(f"orientations must be (M,) with M = {rects.shape[0]} rectangles, got shape {tuple(orientations.shape)}")
    if orientations.numel() and (orientations.min() < 0 or orientations.max() >= n_bins):
        raise ValueError(f"orientations must be in [0, {n_bins}), got range [{int(orientations.min())}, {int(orientations.max())}]")
    ii = orientation_integrals(x, n_bins)
    rects = _check_rects(rects)
    b, k, h1, w1 = ii.shape
    if rects.numel() and (int((rects[:, 0] + rects[:, 2]).max()) > h1 - 1 or int((rects[:, 1] + rects[:, 3]).max()) > w1 - 1):
        raise ValueError(f"a rectangle exceeds the {h1 - 1}x{w1 - 1} image")
    y0, x0 = rects[:, 0], rects[:, 1]
    y1, x1 = y0 + rects[:, 2], x0 + rects[:, 3]
    corners = torch.stack([y1 * w1 + x1, y0 * w1 + x1, y1 * w1 + x0, y0 * w1 + x0]).to(ii.device)  # (4, M)
    # only the learner's own bin and the all-bin total are read: 8 look-ups per learner
    # (index_select along a contiguous row is much faster than 2-D advanced indexing)
    m = corners.shape[1]
    own = ii.reshape(b, k * h1 * w1).index_select(1, (corners + orientations.to(ii.device) * (h1 * w1)).reshape(-1))
    tot = ii.sum(1).reshape(b, h1 * w1).index_select(1, corners.reshape(-1))
    own, tot = own.view(b, 4, m), tot.view(b, 4, m)
    g_o = own[:, 0] - own[:, 1] - own[:, 2] + own[:, 3]
    g = tot[:, 0] - tot[:, 1] - tot[:, 2] + tot[:, 3]
    if floor:
        return g_o / (g + (eps + floor * (rects[:, 2] * rects[:, 3]).to(g.device, g.dtype)))
    return g_o / (g + eps)


def _check_window(window: int, min_size: int) -> None:
    if not isinstance(window, int) or window < 3:
        raise ValueError(f"window must be an int >= 3, got {window}")
    if not isinstance(min_size, int) or not 1 <= min_size <= window - 2:
        raise ValueError(f"min_size must be an int in [1, window - 2 = {window - 2}], got {min_size}")


def random_candidates(
    n: int,
    window: int = 40,
    n_bins: int = 4,
    *,
    generator: torch.Generator,
    min_size: int = 4,
) -> tuple[Tensor, Tensor]:
    """Draw ``n`` random (rectangle, orientation) pairs inside a window's interior.

    Sides are uniform in ``[min_size, window - 2]``, positions uniform among the
    placements inside ``[1, window - 1)``, orientations uniform.

    Args:
        n: number of candidates.
        window: side of the square window.
        n_bins: number of orientation bins K.
        generator: the only source of randomness.
        min_size: smallest rectangle side.

    Returns:
        ``(rects, orientations)`` of shapes ``(n, 4)`` and ``(n,)``, int64.

    Example:
        >>> r, o = random_candidates(100, 40, 4, generator=torch.Generator().manual_seed(1))
        >>> bool((r[:, 0] >= 1).all() and (r[:, 0] + r[:, 2] <= 39).all()), int(o.max()) < 4
        (True, True)
    """
    if not isinstance(n, int) or n < 0:
        raise ValueError(f"n must be an int >= 0, got {n}")
    _check_window(window, min_size)
    _check_n_bins(n_bins)
    inner = window - 2
    hw = torch.randint(min_size, inner + 1, (n, 2), generator=generator)
    # position uniform in [0, inner - side] for each axis
    u = torch.rand(n, 2, generator=generator)
    pos = (u * (inner - hw + 1).double()).floor().long().clamp_max(inner - hw) + 1
    orients = torch.randint(0, n_bins, (n,), generator=generator)
    return torch.cat([pos, hw], dim=1), orients


def exhaustive_candidates(
    window: int = 40,
    n_bins: int = 4,
    *,
    step: int = 4,
    min_size: int = 4,
) -> tuple[Tensor, Tensor]:
    """Every rectangle on a grid of ``step`` pixels inside the window's interior, times every bin.

    Args:
        window: side of the square window.
        n_bins: number of orientation bins K.
        step: grid step of corners and sides.
        min_size: smallest rectangle side (rounded up to a multiple of ``step``).

    Returns:
        ``(rects, orientations)``; each rectangle appears once per bin.

    Example:
        >>> r, o = exhaustive_candidates(10, 2, step=4, min_size=4)
        >>> r.tolist(), o.tolist()
        ([[1, 1, 4, 4], [1, 1, 4, 4], [1, 1, 4, 8], [1, 1, 4, 8], [1, 1, 8, 4], [1, 1, 8, 4], [1, 1, 8, 8], [1, 1, 8, 8], [1, 5, 4, 4], [1, 5, 4, 4], [1, 5, 8, 4], [1, 5, 8, 4], [5, 1, 4, 4], [5, 1, 4, 4], [5, 1, 4, 8], [5, 1, 4, 8], [5, 5, 4, 4], [5, 5, 4, 4]], [0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1])
    """
    _check_window(window, min_size)
    _check_n_bins(n_bins)
    if not isinstance(step, int) or step < 1:
        raise ValueError(f"step must be an int >= 1, got {step}")
    inner = window - 2
    first = step * math.ceil(min_size / step)
    spans = [(p, s) for p in range(0, inner, step) for s in range(first, inner - p + 1, step)]
    rects = [(1 + py, 1 + px, sy, sx) for (py, sy) in spans for (px, sx) in spans]
    rects.sort()
    if not rects:
        raise ValueError(f"no rectangle fits: window {window}, step {step}, min_size {min_size}")
    r = torch.tensor(rects, dtype=torch.long)
    return r.repeat_interleave(n_bins, dim=0), torch.arange(n_bins).repeat(len(rects))


def weak_learner_response(
    energies: Tensor,
    thresholds: Tensor,
    polarity: Tensor | None = None,
    temperature: float | None = None,
) -> Tensor:
    """h = 1[p (E - τ) > 0], or its smooth version σ(p (E - τ) / T).

    Args:
        energies: E values.
        thresholds: τ, one per learner.
        polarity: p ∈ {+1, -1} per learner (all +1 when None, the paper's form).
        temperature: T > 0 for the sigmoid; None for the hard step.

    Shape:
        - energies: (B, M)
        - thresholds, polarity: (M,)
        - output: (B, M)

    Example:
        >>> weak_learner_response(torch.tensor([[0.2, 0.6]]), torch.tensor([0.5, 0.5])).tolist()
        [[0.0, 1.0]]
    """
    z = energies - thresholds
    if polarity is not None:
        z = z * polarity
    if temperature is None:
        return (z > 0).to(energies.dtype)
    if not temperature > 0:
        raise ValueError(f"temperature must be > 0, got {temperature}")
    return torch.sigmoid(z / temperature)


@dataclass
class WeakLearners:
    """A set of M weak learners h_{R,o,τ} with polarity and weight (AdaBoost's α).

    Attributes:
        rects: (M, 4) int64 rectangles ``(y0, x0, h, w)`` in window coordinates.
        orientations: (M,) int64 orientation bins.
        thresholds: (M,) float τ.
        polarity: (M,) float, +1 for ``E > τ``, -1 for ``E < τ``.
        weights: (M,) float α (1 for random learners).
        window: side of the window the rectangles live in.
        n_bins: number of orientation bins K.
        eps: ε of the energy normalisation.
        floor: energy floor per pixel of the normalisation (:func:`edge_orientation_energy`; 0: none).

    Example:
        >>> g = torch.Generator().manual_seed(0)
        >>> wl = WeakLearners.random(8, window=40, generator=g)
        >>> wl.responses(torch.rand(2, 1, 40, 40, generator=g)).shape
        torch.Size([2, 8])
        >>> WeakLearners.from_state_dict(wl.state_dict()).thresholds.equal(wl.thresholds)
        True
    """

    rects: Tensor
    orientations: Tensor
    thresholds: Tensor
    polarity: Tensor
    weights: Tensor
    window: int = 40
    n_bins: int = 4
    eps: float = DEFAULT_EPS
    floor: float = 0.0

    def __post_init__(self) -> None:
        self.rects = _check_rects(self.rects)
        m = self.rects.shape[0]
        self.orientations = torch.as_tensor(self.orientations).long()
        self.thresholds = torch.as_tensor(self.thresholds, dtype=torch.float32)
        self.polarity = torch.as_tensor(self.polarity, dtype=torch.float32)
        self.weights = torch.as_tensor(self.weights, dtype=torch.float32)
        for name in ("orientations", "thresholds", "polarity", "weights"):
            t = getattr(self, name)
            if t.shape != (m,):
                raise ValueError(f"{name} must have shape ({m},) like rects, got {tuple(t.shape)}")
        _check_n_bins(self.n_bins)
        if m and (self.orientations.min() < 0 or self.orientations.max() >= self.n_bins):
            raise ValueError(f"orientations must be in [0, {self.n_bins}), got max {int(self.orientations.max())}")
        if m and int((self.rects[:, :2] + self.rects[:, 2:]).max()) > self.window:
            raise ValueError(f"rectangles must fit in the {self.window}x{self.window} window, "
                             f"got corner {int((self.rects[:, :2] + self.rects[:, 2:]).max())}")
        if not (self.polarity.abs() == 1).all():
            raise ValueError(f"polarity must be +1 or -1, got {self.polarity.unique().tolist()}")
        self.floor = float(self.floor)
        if not (self.floor >= 0 and math.isfinite(self.floor)):
            raise ValueError(f"floor must be finite and >= 0, got {self.floor}")

    def __len__(self) -> int:
        return int(self.rects.shape[0])

    @classmethod
    def random(
        cls,
        n: int,
        window: int = 40,
        n_bins: int = 4,
        *,
        generator: torch.Generator,
        reference: Tensor | None = None,
        min_size: int = 4,
        eps: float = DEFAULT_EPS,
    ) -> "WeakLearners":
        """``n`` random learners with weight 1 (the paper's d_WL^R).

        Args:
            n: number of learners.
            window: window side.
            n_bins: orientation bins K.
            generator: the only source of randomness.
            reference: optional patches ``(N, 1, window, window)``; each τ is then
                the energy of a random reference patch (so every learner splits
                realistic data), otherwise τ ~ U(0, 2 / n_bins) (E averages
                1 / n_bins on isotropic texture, so these thresholds split it).
            min_size: smallest rectangle side.
            eps: ε of the energy.
        """
        rects, orients = random_candidates(n, window, n_bins, generator=generator, min_size=min_size)
        if reference is None:
            tau = torch.rand(n, generator=generator) * (2.0 / n_bins)
        else:
            ref = _check_batch(reference)
            if ref.shape[-2:] != (window, window) or ref.shape[0] == 0:
                raise ValueError(f"reference must be (N>0, 1, {window}, {window}), got {tuple(ref.shape)}")
            e = edge_orientation_energy(ref.float(), rects, orients, n_bins, eps)  # (N, n)
            pick = torch.randint(0, ref.shape[0], (n,), generator=generator)
            tau = e[pick, torch.arange(n)]
        return cls(rects, orients, tau, torch.ones(n), torch.ones(n), window, n_bins, eps)

    def energies(self, x: Tensor) -> Tensor:
        """E(X, R_i, o_i) for every learner, shape (B, M)."""
        return edge_orientation_energy(x, self.rects, self.orientations, self.n_bins, self.eps, self.floor)

    def offsets(self) -> Tensor:
        """Each learner's constant of the normalisation, ``ε + floor · |R|``, float64 (M,)."""
        return self.eps + self.floor * (self.rects[:, 2] * self.rects[:, 3]).double()

    def responses(self, x: Tensor, temperature: float | None = None) -> Tensor:
        """h_i(X) in {0, 1} (or its sigmoid), shape (B, M); ``polarity`` is applied."""
        return weak_learner_response(self.energies(x), self.thresholds.to(x.dtype), self.polarity.to(x.dtype), temperature)

    def subset(self, index: Tensor | slice) -> "WeakLearners":
        """The learners selected by ``index``."""
        return WeakLearners(self.rects[index], self.orientations[index], self.thresholds[index],
                            self.polarity[index], self.weights[index], self.window, self.n_bins, self.eps, self.floor)

    def state_dict(self) -> dict[str, Any]:
        """Tensors and plain Python values only (loads with ``weights_only=True``)."""
        return {
            "rects": self.rects.clone(), "orientations": self.orientations.clone(),
            "thresholds": self.thresholds.clone(), "polarity": self.polarity.clone(),
            "weights": self.weights.clone(), "window": int(self.window),
            "n_bins": int(self.n_bins), "eps": float(self.eps), "floor": float(self.floor),
        }

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> "WeakLearners":
        """Inverse of :meth:`state_dict`; raises KeyError/ValueError on a bad state."""
        return cls(state["rects"], state["orientations"], state["thresholds"], state["polarity"],
                   state["weights"], int(state["window"]), int(state["n_bins"]), float(state["eps"]),
                   float(state.get("floor", 0.0)))  # files written before the floor have none
