"""Histograms of Oriented Gradients (Dalal & Triggs 2005) in torch, batched.

Pipeline, each stage a pure function on ``(B, ..., H, W)`` tensors:

1. :func:`image_gradients` — centred differences ``[-1, 0, 1]``, zero on the
   image's first/last row and column (``skimage.feature.hog``'s convention);
2. :func:`orientation_votes` — each pixel votes its gradient magnitude into
   *unsigned* orientation bins over [0°, 180°): ``"hard"`` binning (the bin
   containing the angle — exactly skimage) or ``"soft"`` binning (linear
   interpolation between the two nearest bin centres, circular — Dalal–Triggs'
   orientation interpolation; smooth in the angle, better for fitting Θ);
3. :func:`cell_histograms` — mean vote over ``cell x cell`` pixel cells
   (skimage divides by the cell area too); with ``stride < cell`` the cells
   overlap and form a *dense* cell map used by sliding-window detection;
4. :func:`block_features` — blocks of ``2 x 2`` cells, L2-Hys normalised
   (L2, clip at 0.2, L2 again; eps = 1e-5 as skimage).

:func:`hog` gives the descriptor of whole patches in skimage's order
``(block_row, block_col, cell_row, cell_col, orientation)`` — a 40×40 patch with
8-px cells has 5×5 cells, 4×4 blocks, 576 values. With ``HOGConfig(binning="hard")``
(:data:`SKIMAGE_HOG`) it equals
``skimage.feature.hog(x, 9, (8, 8), (2, 2), "L2-Hys")`` to float precision.

:func:`dense_block_map` computes blocks for every window position of a whole
image at a pixel stride dividing the cell size; a linear filter over a window
is then one dilated ``conv2d`` over this map (see
:class:`synthaug.detectors.hog_dpm.HOGDetector`). Windows of the dense map
differ from :func:`hog` of the cropped window only on the window's outer
pixel ring, where a crop sees zero gradient and the full image does not.

Multi-channel input is processed per channel (features concatenated), not with
skimage's "channel of largest gradient" rule.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Literal

import torch
import torch.nn.functional as F
from torch import Tensor


@dataclass(frozen=True)
class HOGConfig:
    """HOG hyper-parameters (discrete choices: flags, not fitted).

    Args:
        orientations: number of unsigned orientation bins over [0°, 180°).
        cell_size: cell side in pixels.
        block_size: block side in cells.
        binning: ``"hard"`` (skimage) or ``"soft"`` (linear between bin centres).
        block_norm: ``"L2-Hys"`` or ``"L2"``.
        clip: L2-Hys clipping value.
        eps: normalisation epsilon (skimage: 1e-5, added as eps² under the root).
        transform_sqrt: apply ``sqrt`` to the image first (gamma compression).
    """

    orientations: int = 9
    cell_size: int = 8
    block_size: int = 2
    binning: Literal["hard", "soft"] = "soft"
    block_norm: Literal["L2-Hys", "L2"] = "L2-Hys"
    clip: float = 0.2
    eps: float = 1e-5
    transform_sqrt: bool = False

    def __post_init__(self) -> None:
        if self.orientations < 1:
            raise ValueError(f"orientations must be >= 1, got {self.orientations}")
        if self.cell_size < 1:
            raise ValueError(f"cell_size must be >= 1, got {self.cell_size}")
        if self.block_size < 1:
            raise ValueError(f"block_size must be >= 1, got {self.block_size}")
        if self.binning not in ("hard", "soft"):
            raise ValueError(f"binning must be 'hard' or 'soft', got {self.binning!r}")
        if self.block_norm not in ("L2-Hys", "L2"):
            raise ValueError(f"block_norm must be 'L2-Hys' or 'L2', got {self.block_norm!r}")
        if not (self.clip > 0 and math.isfinite(self.clip)):
            raise ValueError(f"clip must be a positive number, got {self.clip}")
        if not self.eps > 0:
            raise ValueError(f"eps must be > 0, got {self.eps}")

    @property
    def block_channels(self) -> int:
        """Values per block: ``block_size² · orientations`` (36 by default)."""
        return self.block_size * self.block_size * self.orientations

    def descriptor_length(self, height: int, width: int) -> int:
        """Length of :func:`hog` for an ``height x width`` patch.

        Example:
            >>> HOGConfig().descriptor_length(40, 40)
            576
        """
        blocks_h = height // self.cell_size - self.block_size + 1
        blocks_w = width // self.cell_size - self.block_size + 1
        if blocks_h < 1 or blocks_w < 1:
            raise ValueError(
                f"a {height}x{width} image is smaller than one block of "
                f"{self.block_size}x{self.block_size} cells of {self.cell_size} px"
            )
        return blocks_h * blocks_w * self.block_channels


DEFAULT_HOG = HOGConfig()
"""Soft orientation binning: the default of the detector and of ``d_hog``."""

SKIMAGE_HOG = HOGConfig(binning="hard")
"""The reference mode: equals ``skimage.feature.hog(..., block_norm="L2-Hys")``."""


def _check_images(images: Tensor) -> Tensor:
    if not isinstance(images, Tensor):
        raise ValueError(f"images must be a torch.Tensor, got {type(images).__name__}")
    if images.dim() != 4:
        raise ValueError(f"images must be (B, C, H, W), got shape {tuple(images.shape)}")
    if not images.dtype.is_floating_point:
        raise ValueError(f"images must be a float tensor, got dtype {images.dtype}")
    return images


def image_gradients(images: Tensor) -> tuple[Tensor, Tensor]:
    """Centred-difference gradients, zero on the image border.

    Args:
        images: float images.

    Returns:
        ``(g_row, g_col)``: ``g_row[y] = I[y+1] - I[y-1]`` (down), ``g_col[x] =
        I[x+1] - I[x-1]`` (right); rows 0 and H-1 of ``g_row`` and columns 0 and
        W-1 of ``g_col`` are zero.

    Shape:
        - images: (B, C, H, W)
        - outputs: (B, C, H, W) each

    Example:
        >>> img = torch.arange(4.).reshape(1, 1, 1, 4)
        >>> image_gradients(img)[1]
        tensor([[[[0., 2., 2., 0.]]]])
    """
    images = _check_images(images)
    g_row = F.pad(images[..., 2:, :] - images[..., :-2, :], (0, 0, 1, 1))
    g_col = F.pad(images[..., :, 2:] - images[..., :, :-2], (1, 1, 0, 0))
    return g_row, g_col


def _gradient_bins(images: Tensor, config: HOGConfig) -> tuple[int, Tensor, list[tuple[int, Tensor]]]:
    """Per-pixel slot index (B, C, H, W) and ``(slot offset, vote)`` pairs: one (hard) or two (soft).

    Slots are *extended* bins so that no index needs wrapping at full resolution
    (a per-pixel where/remainder costs more than the whole scatter): ``hard``
    uses slots ``0..O`` (slot ``O`` = an angle of exactly 180°, dropped);
    ``soft`` uses ``0..O+1``, slot ``s`` meaning bin ``s - 1`` with slot 0 = bin
    ``O - 1`` and slot ``O + 1`` = bin 0. :func:`_fold_slots` maps them back.

    Returns:
        ``(number of slots, index, [(offset, vote), ...])``: each vote goes to slot
        ``index + offset``.
    """
    if config.transform_sqrt:
        images = images.clamp_min(0).sqrt()
    g_row, g_col = image_gradients(images)
    sq = g_row * g_row + g_col * g_col
    if torch.is_grad_enabled() and images.requires_grad:
        # where() keeps gradients finite at zero-gradient pixels (sqrt and atan2 are singular there)
        nonzero = sq > 0
        magnitude = torch.where(nonzero, torch.sqrt(torch.where(nonzero, sq, torch.ones_like(sq))), torch.zeros_like(sq))
        angle = torch.atan2(torch.where(nonzero, g_row, torch.zeros_like(g_row)), torch.where(nonzero, g_col, torch.ones_like(g_col)))
    else:
        magnitude = torch.sqrt(sq)
        angle = torch.atan2(g_row, g_col)  # atan2(0, 0) = 0: a zero vote in bin 0
    n = config.orientations
    # atan2 is in (-pi, pi]: fold to [0, pi] in bin units; a position of exactly n
    # (angle ±pi) is an angle of 0 for skimage's `% 180`
    position = angle * (n / math.pi)
    position = torch.where(position < 0, position + n, position)
    if config.binning == "hard":
        # bin k holds [k, k+1) bin widths; position n (exactly 180°) lands in slot n,
        # folded back into bin 0 as skimage does
        return n + 1, position.floor().long(), [(0, magnitude)]
    # bin centres at (k + 1/2) widths; the vote is split linearly between the two
    # nearest centres, circularly (0° and 180° are the same orientation)
    centred = position + 0.5  # = (position - 0.5) + 1: slot of the lower centre
    low = centred.floor()
    high_weight = magnitude * (centred - low)
    return n + 2, low.long(), [(0, magnitude - high_weight), (1, high_weight)]


def _fold_slots(slots: Tensor, config: HOGConfig, dim: int) -> Tensor:
    """Extended slots of :func:`_gradient_bins` (along ``dim``) -> ``O`` orientation bins."""
    n = config.orientations
    if config.binning == "hard":
        main = slots.narrow(dim, 0, n).clone()
        main.narrow(dim, 0, 1).add_(slots.narrow(dim, n, 1))
        return main
    main = slots.narrow(dim, 1, n).clone()
    main.narrow(dim, n - 1, 1).add_(slots.narrow(dim, 0, 1))
    main.narrow(dim, 0, 1).add_(slots.narrow(dim, n + 1, 1))
    return main


def orientation_votes(images: Tensor, config: HOGConfig = DEFAULT_HOG) -> Tensor:
    """Per-pixel gradient magnitude split into unsigned orientation bins.

    Bin ``k`` covers angles ``[k·180/O, (k+1)·180/O)``, angles measured as
    ``atan2(g_row, g_col)`` mod 180° (skimage's convention, rows pointing down).

    Args:
        images: float images.
        config: HOG settings (``orientations``, ``binning``, ``transform_sqrt``).

    Returns:
        Votes; summing over the orientation axis gives the gradient magnitude.

    Shape:
        - images: (B, C, H, W)
        - output: (B, C * O, H, W), channel-major (all bins of channel 0 first).

    Example:
        >>> x = torch.tensor([0., 0., 1., 1.]).repeat(4, 1)[None, None]  # vertical edge
        >>> orientation_votes(x, SKIMAGE_HOG)[0, :, 1, 1]  # 0° -> bin 0
        tensor([1., 0., 0., 0., 0., 0., 0., 0., 0.])
    """
    images = _check_images(images)
    b, c, h, w = images.shape
    n_slots, index, pairs = _gradient_bins(images, config)
    votes = images.new_zeros(b, c, n_slots, h, w)
    for offset, vote in pairs:
        votes = votes.scatter_add(2, (index + offset).unsqueeze(2), vote.unsqueeze(2))
    return _fold_slots(votes, config, dim=2).reshape(b, c * config.orientations, h, w)


def _subcell_sums(images: Tensor, config: HOGConfig, sub: int) -> Tensor:
    """Mean orientation votes over disjoint ``sub x sub`` pixel blocks, ``(B, C*O, H//sub, W//sub)``.

    One scatter of every pixel's vote straight into its (sub-cell, slot) entry:
    far cheaper than materialising (B, C, O, H, W) votes and pooling them.
    """
    b, c, h, w = images.shape
    hs, ws = h // sub, w // sub
    n_slots, index, pairs = _gradient_bins(images, config)
    first_slot = _first_slots(hs, ws, sub, n_slots, images.device)
    size = hs * ws * n_slots
    sums = images.new_zeros(b, c, size + max(offset for offset, _ in pairs))
    pixels = hs * sub * ws * sub
    # the add writes the cropped indices contiguously: no separate copy of the crop
    target = (first_slot + index[..., : hs * sub, : ws * sub]).reshape(b, c, pixels)
    for offset, vote in pairs:
        vote = vote[..., : hs * sub, : ws * sub].reshape(b, c, pixels)
        # slot + offset: the same indices into a view shifted by offset (same order of accumulation)
        sums.narrow(2, offset, size).scatter_add_(2, target, vote)
    sums = _fold_slots(sums.narrow(2, 0, size).reshape(b, c, hs, ws, n_slots), config, dim=4)
    sums = sums.permute(0, 1, 4, 2, 3).reshape(b, c * config.orientations, hs, ws)
    return sums / float(sub * sub)


@functools.lru_cache(maxsize=32)
def _first_slots(hs: int, ws: int, sub: int, n_slots: int, device: torch.device) -> Tensor:
    """Index of the first slot of each pixel's sub-cell, ``(hs * sub, ws * sub)`` int64 (cached: pyramid sizes repeat).

    Read-only: callers must not modify it in place.
    """
    rows = torch.arange(hs * sub, device=device) // sub
    cols = torch.arange(ws * sub, device=device) // sub
    return (rows[:, None] * ws + cols[None, :]) * n_slots


def cell_histograms(images: Tensor, config: HOGConfig = DEFAULT_HOG, stride: int | None = None) -> Tensor:
    """Orientation histograms of ``cell x cell`` cells (mean vote per pixel).

    Args:
        images: float images.
        config: HOG settings.
        stride: pixel step between cells; ``None`` = ``cell_size`` (disjoint
            cells, skimage). A smaller stride gives the dense map of
            :func:`dense_block_map`.

    Returns:
        Cell histograms; partial cells at the right/bottom border are dropped.

    Shape:
        - images: (B, C, H, W)
        - output: (B, C * O, (H - cell) // stride + 1, (W - cell) // stride + 1)
    """
    stride = config.cell_size if stride is None else int(stride)
    if stride < 1:
        raise ValueError(f"stride must be >= 1, got {stride}")
    images = _check_images(images)
    cell = config.cell_size
    if images.shape[-2] < cell or images.shape[-1] < cell:
        raise ValueError(f"image of size {tuple(images.shape[-2:])} is smaller than one {cell}-px cell")
    if cell % stride == 0:
        # an 8-px cell at stride 4 is the mean of 2x2 disjoint 4-px sub-cells
        sub = _subcell_sums(images, config, stride)
        k = cell // stride
        if k == 1:
            return sub
        # k x k stride-1 mean as k*k shifted slices: cheaper than avg_pool2d on CPU for small k
        hc, wc = sub.shape[-2] - k + 1, sub.shape[-1] - k + 1
        total = sub[..., :hc, :wc]
        for i in range(k):
            for j in range(k):
                if i or j:
                    total = total + sub[..., i : i + hc, j : j + wc]
        return total / float(k * k)
    votes = orientation_votes(images, config)
    return F.avg_pool2d(votes, kernel_size=cell, stride=stride)


def block_features(cells: Tensor, config: HOGConfig = DEFAULT_HOG, dilation: int = 1) -> Tensor:
    """Normalised blocks of ``block_size x block_size`` cells.

    Args:
        cells: cell histograms from :func:`cell_histograms` (one image channel:
            ``O`` channels; several image channels: ``C * O``, normalised per
            image channel).
        config: HOG settings.
        dilation: step, in cell-map positions, between the cells of one block
            (``cell_size // stride`` for a dense map).

    Returns:
        Blocks, channel order ``(image_channel, cell_row, cell_col, orientation)``.

    Shape:
        - cells: (B, C * O, Hc, Wc)
        - output: (B, C * b * b * O, Hc - (b - 1) * dilation, Wc - (b - 1) * dilation)
    """
    n, b = config.orientations, config.block_size
    batch, cn, hc, wc, hb, wb = _block_map_shape(cells, config, dilation)
    grouped = cells.reshape(batch, cn // n, n, hc, wc)
    parts = [grouped[..., i * dilation : i * dilation + hb, j * dilation : j * dilation + wb] for i in range(b) for j in range(b)]
    blocks = torch.stack(parts, dim=2)  # (B, C, b*b, O, Hb, Wb)
    blocks = blocks.reshape(batch, cn // n, b * b * n, hb, wb)
    eps2 = config.eps * config.eps
    blocks = blocks / torch.sqrt((blocks * blocks).sum(2, keepdim=True) + eps2)
    if config.block_norm == "L2-Hys":
        blocks = blocks.clamp_max(config.clip)
        blocks = blocks / torch.sqrt((blocks * blocks).sum(2, keepdim=True) + eps2)
    return blocks.reshape(batch, (cn // n) * b * b * n, hb, wb)


def hog(images: Tensor, config: HOGConfig = DEFAULT_HOG) -> Tensor:
    """HOG descriptors of whole images (patches), in skimage's order.

    Args:
        images: float images, typically 40×40 grayscale patches in [0, 1].
        config: HOG settings; :data:`SKIMAGE_HOG` reproduces
            ``skimage.feature.hog(x, orientations=9, pixels_per_cell=(8, 8),
            cells_per_block=(2, 2), block_norm="L2-Hys")``.

    Returns:
        One descriptor per image, order ``(block_row, block_col, cell_row,
        cell_col, orientation)`` (channels, if several, outermost).

    Shape:
        - images: (B, C, H, W)
        - output: (B, C * config.descriptor_length(H, W))

    Example:
        >>> x = torch.rand(2, 1, 40, 40, generator=torch.Generator().manual_seed(0))
        >>> hog(x).shape
        torch.Size([2, 576])
    """
    images = _check_images(images)
    config.descriptor_length(images.shape[-2], images.shape[-1])  # validates the size
    blocks = block_features(cell_histograms(images, config), config)  # (B, C*bbO, Hb, Wb)
    batch, channels = images.shape[:2]
    per_channel = blocks.reshape(batch, channels, config.block_channels, *blocks.shape[-2:])
    return per_channel.permute(0, 1, 3, 4, 2).reshape(batch, channels * config.block_channels * blocks.shape[-2] * blocks.shape[-1])


def dense_block_map(image: Tensor, config: HOGConfig = DEFAULT_HOG, stride: int = 4) -> Tensor:
    """Normalised HOG blocks at every ``stride``-pixel position of an image.

    ``out[:, :, y, x]`` is the block whose top-left cell starts at pixel
    ``(y * stride, x * stride)``; the block ``(i, j)`` of a window with top-left
    ``(Y, X)`` (both multiples of ``stride``) is at ``(Y / stride + i * d,
    X / stride + j * d)`` with ``d = cell_size // stride``.

    Args:
        image: float image(s).
        config: HOG settings.
        stride: pixel step; must divide ``cell_size``.

    Shape:
        - image: (B, C, H, W)
        - output: (B, C * b * b * O, (H - cell) // stride + 1 - (b - 1) * d, same for W)
    """
    if stride < 1 or config.cell_size % stride:
        raise ValueError(f"stride must divide cell_size={config.cell_size}, got {stride}")
    cells = cell_histograms(image, config, stride=stride)
    if torch.is_grad_enabled() and cells.requires_grad:
        return block_features(cells, config, dilation=config.cell_size // stride)
    return _dense_block_features(cells, config, dilation=config.cell_size // stride)


def _block_map_shape(cells: Tensor, config: HOGConfig, dilation: int) -> tuple[int, int, int, int, int, int]:
    """``(B, C*O, Hc, Wc, Hb, Wb)`` of a cell map and its block map; ValueError for a map that holds no block."""
    n, b = config.orientations, config.block_size
    if cells.dim() != 4 or cells.shape[1] % n:
        raise ValueError(f"cells must be (B, C*{n}, Hc, Wc), got shape {tuple(cells.shape)}")
    batch, cn, hc, wc = cells.shape
    span = (b - 1) * dilation
    if hc <= span or wc <= span:
        raise ValueError(f"a cell map of size {(hc, wc)} holds no {b}x{b} block (dilation {dilation})")
    return batch, cn, hc, wc, hc - span, wc - span


def _dense_block_features(cells: Tensor, config: HOGConfig, dilation: int) -> Tensor:
    """:func:`block_features` without autograd, for dense maps (equal up to float rounding).

    The first normalisation's sum of squares comes from per-cell sums (a block's
    cells are shared by ``b * b`` blocks: 4x less work), and the normalisations
    run in place on the stacked blocks; each pass over the ``b * b * O``-channel
    map is memory-bound on a full frame.
    """
    n, b = config.orientations, config.block_size
    batch, cn, hc, wc, hb, wb = _block_map_shape(cells, config, dilation)
    grouped = cells.reshape(batch, cn // n, n, hc, wc)
    offsets = [(i * dilation, j * dilation) for i in range(b) for j in range(b)]
    cell_sq = (grouped * grouped).sum(2)  # (B, C, Hc, Wc)
    sq = cell_sq[..., :hb, :wb].clone()
    for y, x in offsets[1:]:
        sq.add_(cell_sq[..., y : y + hb, x : x + wb])
    eps2 = config.eps * config.eps
    blocks = torch.stack([grouped[..., y : y + hb, x : x + wb] for y, x in offsets], dim=2)
    blocks = blocks.reshape(batch, cn // n, b * b * n, hb, wb)
    blocks.div_(sq.add_(eps2).sqrt_().unsqueeze(2))
    if config.block_norm == "L2-Hys":
        blocks.clamp_max_(config.clip)
        blocks.div_((blocks * blocks).sum(2, keepdim=True).add_(eps2).sqrt_())
    return blocks.reshape(batch, (cn // n) * b * b * n, hb, wb)


def descriptor_to_filter(weights: Tensor, config: HOGConfig, window: int) -> Tensor:
    """Reshape linear weights over :func:`hog` descriptors into conv2d filters over block maps.

    ``(hog(patch) * w).sum()`` equals the dilated convolution of the patch's
    block map with ``descriptor_to_filter(w)``.

    Args:
        weights: one weight vector per filter, in :func:`hog` order (one channel).
        config: the HOG settings the weights were trained with.
        window: patch side in pixels.

    Shape:
        - weights: (K, D)
        - output: (K, b * b * O, Hb, Wb), Hb = Wb = window // cell - b + 1
    """
    blocks = window // config.cell_size - config.block_size + 1
    expected = config.descriptor_length(window, window)
    if weights.dim() != 2 or weights.shape[1] != expected:
        raise ValueError(f"weights must be (K, {expected}) for a {window}-px window, got shape {tuple(weights.shape)}")
    return weights.reshape(-1, blocks, blocks, config.block_channels).permute(0, 3, 1, 2).contiguous()
