"""The HOG detector of the DPM family: a mixture of linear root filters on HOG.

What this is — the parts of Felzenszwalb et al.'s DPM (PAMI 2010) that carry
over to 40×40 windows:

- HOG features (:mod:`synthaug.detectors.hog`: Dalal–Triggs 9 unsigned bins,
  8-px cells, 2×2-cell L2-Hys blocks; soft orientation binning by default);
- a *mixture* of ``K`` linear **root filters** (components; 3 by default, the
  paper uses 3–5), the score of a window being the max over components;
- components initialised by k-means on the positives' HOG vectors, then
  **latent re-assignment** of every positive to its best-scoring component and
  retraining (the latent-SVM alternation of DPM, on the component label only);
- per-component linear SVMs (squared hinge, L2 regularisation, class-balanced,
  solved with L-BFGS in the primal) trained with **hard-negative mining**: a
  cache of negatives is retrained on, the whole negative pool (patches and,
  optionally, every window of background frames) is rescanned, margin
  violators are added and easy negatives dropped, for a few rounds;
- dense sliding-window scoring: HOG blocks computed once per pyramid level,
  each root filter applied as one dilated ``conv2d``.

What this is not: there are **no deformable parts** (no part filters at twice
the resolution, no deformation costs, no distance transforms), no
Felzenszwalb 31-dimensional PCA-like HOG, no bounding-box regression, no
mirrored component pairs (``mirror=True`` only adds flipped positives), and
the components are trained one-vs-negatives, not jointly in one latent SVM.
At 40×40 pixels — 5×5 cells — a drone or airplane leaves little room for parts.

Example:
    >>> import torch
    >>> g = torch.Generator().manual_seed(0)
    >>> pos = torch.rand(30, 1, 40, 40, generator=g) * 0.2
    >>> pos[:, :, 15:25, 10:30] += 0.7                  # a bright bar: "the object"
    >>> neg = torch.rand(60, 1, 40, 40, generator=g)
    >>> det = HOGDetector.fit(pos, neg, components=2, generator=g)
    >>> bool((det.score_patches(pos) > det.score_patches(neg).max()).float().mean() > 0.9)
    True
"""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any, Sequence

import torch
from torch import Tensor

from synthaug.detectors.base import (PatchDetector, check_image, check_weights, register_detector, score_map_shape,
                                     to_float_patches)
from synthaug.detectors.hog import DEFAULT_HOG, HOGConfig, dense_block_map, descriptor_to_filter, hog


def _hog_chunked(patches: Tensor, config: HOGConfig, chunk: int = 4096) -> Tensor:
    if patches.shape[0] == 0:
        return patches.new_zeros(0, config.descriptor_length(patches.shape[-2], patches.shape[-1]))
    return torch.cat([hog(p, config) for p in patches.split(chunk)])


def kmeans(x: Tensor, k: int, *, generator: torch.Generator, iterations: int = 30, restarts: int = 1) -> Tensor:
    """k-means with k-means++ seeding, the best of ``restarts`` runs; returns the label of every row.

    Lloyd's iterations stop in a local minimum that depends on the seeding. Each restart draws a new
    seeding from ``generator`` (in turn) and the run with the lowest inertia (sum of squared distances to
    the cluster means) wins, the earliest on ties: scikit-learn's ``KMeans(n_init=restarts)``.

    Args:
        x: points.
        k: number of clusters (clipped to the number of points).
        generator: the only source of randomness (seeding).
        iterations: Lloyd iterations per run.
        restarts: runs (≥ 1). One run lands in a worse minimum often enough to matter: on the 11,608
            all-frames drone positives (HOG, k = 3) 3 of 10 seedings end at inertia 53,946 instead of
            53,380, and those HOG detectors fire on ground texture (``results/learning_curve/mining_collapse/``).

    Shape:
        - x: (N, D)
        - output: (N,) int64 labels in [0, k)

    Example:
        >>> pts = torch.tensor([[0.], [0.1], [10.], [10.1]])
        >>> labels = kmeans(pts, 2, generator=torch.Generator().manual_seed(0))
        >>> bool(labels[0] == labels[1] and labels[2] == labels[3] and labels[0] != labels[2])
        True
    """
    if restarts < 1:
        raise ValueError(f"restarts must be >= 1, got {restarts}")
    best: tuple[float, Tensor] | None = None
    for _ in range(restarts):
        labels, inertia = _kmeans_once(x, k, generator=generator, iterations=iterations)
        if best is None or inertia < best[0]:
            best = (inertia, labels)
    assert best is not None
    return best[1]


def kmeans_inertia(x: Tensor, labels: Tensor) -> float:
    """Sum of squared distances of the rows of ``x`` to the mean of their cluster (k-means' objective)."""
    _, inverse = torch.unique(labels, return_inverse=True)
    means = torch.zeros(int(inverse.max()) + 1, x.shape[1], dtype=torch.float64).index_add_(0, inverse, x.double())
    means /= torch.bincount(inverse).double()[:, None]
    return float(((x.double() - means[inverse]) ** 2).sum())


def _kmeans_once(x: Tensor, k: int, *, generator: torch.Generator, iterations: int) -> tuple[Tensor, float]:
    """One k-means++ seeding and its Lloyd iterations: (labels, inertia)."""
    n = x.shape[0]
    k = max(1, min(int(k), n))
    first = int(torch.randint(n, (1,), generator=generator))
    centres = [x[first]]
    d2 = ((x - centres[0]) ** 2).sum(1)
    for _ in range(1, k):
        probs = d2 / d2.sum() if d2.sum() > 0 else torch.full_like(d2, 1.0 / n)
        idx = int(torch.multinomial(probs, 1, generator=generator))
        centres.append(x[idx])
        d2 = torch.minimum(d2, ((x - x[idx]) ** 2).sum(1))
    c = torch.stack(centres)
    labels = torch.cdist(x, c).argmin(1)
    for _ in range(iterations):
        new_c = torch.stack([x[labels == j].mean(0) if (labels == j).any() else c[j] for j in range(k)])
        new_labels = torch.cdist(x, new_c).argmin(1)
        c = new_c
        if torch.equal(new_labels, labels):
            break
        labels = new_labels
    return labels, kmeans_inertia(x, labels)


def train_linear_svm(
    features: Tensor,
    labels: Tensor,
    *,
    regularization: float = 1e-3,
    max_iter: int = 200,
    init: tuple[Tensor, Tensor] | None = None,
    sample_weight: Tensor | None = None,
) -> tuple[Tensor, Tensor]:
    """Class-balanced L2-regularised squared-hinge linear SVM, primal, L-BFGS.

    Minimises ``λ/2 ||w||² + Σ_i c_i max(0, 1 - y_i (w·x_i + b))²`` with
    ``c_i = 1 / (2 N_{y_i})`` (each class weighs one half); the bias is not
    regularised. With ``sample_weight`` (≥ 0), ``c_i = s_i / (2 Σ_{j: y_j = y_i} s_j)``:
    each class still weighs one half, shared in proportion to the weights (a weight of 2 counts
    as the sample twice).

    Args:
        features: training vectors.
        labels: ``+1`` (object) or ``-1`` (background).
        regularization: λ.
        max_iter: L-BFGS iterations.
        init: warm start ``(w, b)``.
        sample_weight: ``(N,)`` non-negative weights (None: all equal).

    Returns:
        ``(w, b)``, shapes ``(D,)`` and ``()``.

    Shape:
        - features: (N, D), labels: (N,)
    """
    if regularization <= 0:
        raise ValueError(f"regularization must be > 0, got {regularization}")
    x = features.double()
    y = labels.double()
    n_pos = int((y > 0).sum())
    n_neg = int((y < 0).sum())
    if n_pos == 0 or n_neg == 0:
        raise ValueError(f"an SVM needs both classes, got {n_pos} positives and {n_neg} negatives")
    if sample_weight is None:
        cost = torch.where(y > 0, 0.5 / n_pos, 0.5 / n_neg)
    else:
        sw = torch.as_tensor(sample_weight).double().reshape(-1)
        if sw.shape != y.shape or not bool(torch.isfinite(sw).all()) or bool((sw < 0).any()):
            raise ValueError(f"sample_weight must be {tuple(y.shape)} finite and >= 0, got {tuple(sw.shape)}")
        w_pos, w_neg = float(sw[y > 0].sum()), float(sw[y < 0].sum())
        if w_pos <= 0 or w_neg <= 0:
            raise ValueError("sample_weight gives a class no weight at all")
        cost = torch.where(y > 0, 0.5 * sw / w_pos, 0.5 * sw / w_neg)
    w = (init[0].double().clone() if init is not None else torch.zeros(x.shape[1], dtype=torch.float64)).requires_grad_(True)
    b = (init[1].double().clone().reshape(()) if init is not None else torch.zeros((), dtype=torch.float64)).requires_grad_(True)
    opt = torch.optim.LBFGS([w, b], lr=1.0, max_iter=max_iter, line_search_fn="strong_wolfe", tolerance_grad=1e-9, tolerance_change=1e-12)

    def closure() -> Tensor:
        opt.zero_grad()
        margin = torch.relu(1.0 - y * (x @ w + b))
        loss = 0.5 * regularization * (w * w).sum() + (cost * margin * margin).sum()
        loss.backward()
        return loss

    with torch.enable_grad():
        opt.step(closure)
    return w.detach().float(), b.detach().float()


@register_detector
class HOGDetector(PatchDetector):
    """Mixture of linear HOG root filters (DPM family, no parts); see the module docstring.

    ``score(X) = max_k (w_k · HOG(X) + b_k)``; the decision threshold is 0.

    Args:
        weights: one root filter per component over :func:`~synthaug.detectors.hog.hog`
            descriptors of a ``window``-px patch.
        bias: one bias per component.
        window: patch side in pixels (a multiple of the cell size).
        stride: pixel step of :meth:`score_map`; must divide the cell size (1, 2, 4, 8).
        config: HOG settings the filters were trained with.

    Shape:
        - weights: (K, D), D = config.descriptor_length(window, window)
        - bias: (K,)
    """

    kind = "hog"

    def __init__(
        self,
        weights: Tensor,
        bias: Tensor,
        *,
        window: int = 40,
        stride: int = 4,
        config: HOGConfig = DEFAULT_HOG,
    ) -> None:
        if not isinstance(config, HOGConfig):
            raise ValueError(f"config must be a HOGConfig, got {type(config).__name__}")
        if window % config.cell_size:
            raise ValueError(f"window must be a multiple of cell_size={config.cell_size}, got {window}")
        if stride < 1 or config.cell_size % stride:
            raise ValueError(f"stride must divide cell_size={config.cell_size}, got {stride}")
        expected = config.descriptor_length(window, window)
        weights = torch.as_tensor(weights, dtype=torch.float32)
        bias = torch.as_tensor(bias, dtype=torch.float32).reshape(-1)
        if weights.dim() != 2 or weights.shape[1] != expected or weights.shape[0] < 1:
            raise ValueError(f"weights must be (K >= 1, {expected}), got shape {tuple(weights.shape)}")
        if bias.shape != (weights.shape[0],):
            raise ValueError(f"bias must be ({weights.shape[0]},), got shape {tuple(bias.shape)}")
        self.weights = weights
        self.bias = bias
        self.window = int(window)
        self.stride = int(stride)
        self.config = config
        self._filters = descriptor_to_filter(weights, config, self.window)

    @property
    def components(self) -> int:
        """Number of root filters K."""
        return int(self.weights.shape[0])

    def features(self, patches: Tensor) -> Tensor:
        """HOG descriptors ``(N, D)`` of float patches ``(N, 1, window, window)``."""
        return _hog_chunked(to_float_patches(patches, self.window), self.config)

    def component_scores(self, patches: Tensor) -> Tensor:
        """Score of every component, shape ``(N, K)``."""
        return self.features(patches) @ self.weights.T + self.bias

    @torch.no_grad()
    def score_patches(self, patches: Tensor) -> Tensor:
        return self.component_scores(patches).amax(1)

    @torch.no_grad()
    def score_map(self, image: Tensor) -> Tensor:
        image = check_image(image)
        h_out, w_out = score_map_shape(image.shape[-2], image.shape[-1], self.window, self.stride)
        if h_out == 0 or w_out == 0:
            return image.new_zeros(h_out, w_out)
        blocks = dense_block_map(image, self.config, self.stride)[0]  # (D_block, Hb, Wb)
        dilation = self.config.cell_size // self.stride
        # dilated conv2d(blocks, filters) as one matmul (every filter tap at every
        # position) plus shifted sums: ~2x faster than conv2d's dilated path on CPU
        k, channels, taps_h, taps_w = self._filters.shape
        hb, wb = blocks.shape[-2:]
        taps = self._filters.permute(0, 2, 3, 1).reshape(k * taps_h * taps_w, channels)
        per_tap = (taps @ blocks.reshape(channels, hb * wb)).reshape(k, taps_h, taps_w, hb, wb)
        scores = per_tap[:, 0, 0, :h_out, :w_out] + self.bias[:, None, None]
        for i in range(taps_h):
            for j in range(taps_w):
                if i or j:
                    scores = scores + per_tap[:, i, j, i * dilation : i * dilation + h_out, j * dilation : j * dilation + w_out]
        return scores.amax(0)

    def state_dict(self) -> dict[str, Any]:
        return {
            "weights": self.weights.clone(),
            "bias": self.bias.clone(),
            "window": self.window,
            "stride": self.stride,
            "config": asdict(self.config),
        }

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> "HOGDetector":
        return cls(
            state["weights"],
            state["bias"],
            window=int(state["window"]),
            stride=int(state["stride"]),
            config=HOGConfig(**state["config"]),
        )

    @classmethod
    def fit(
        cls,
        positives: Tensor,
        negatives: Tensor,
        *,
        background_images: Sequence[Tensor] = (),
        ignore_boxes: Sequence[Tensor | None] | None = None,
        components: int = 3,
        window: int = 40,
        stride: int = 4,
        config: HOGConfig = DEFAULT_HOG,
        regularization: float = 1e-3,
        mining_rounds: int = 3,
        latent_rounds: int = 1,
        initial_negatives: int = 4000,
        max_negative_cache: int = 20000,
        kmeans_restarts: int = 10,
        mine_scales: Sequence[float] = (1.0, 0.71, 0.5),
        mirror: bool = True,
        generator: torch.Generator | None = None,
        verbose: bool = False,
        positive_weights: Tensor | None = None,
    ) -> "HOGDetector":
        """Train the mixture with k-means initialisation, latent re-assignment and hard-negative mining.

        Args:
            positives: object patches (uint8 0..255 or float 0..1).
            negatives: background patches, the mining pool.
            background_images: optional frames (``(H, W)`` float in [0, 1]);
                every window at ``mine_scales`` is part of the mining pool.
            ignore_boxes: per background image, ``(G, 4)`` ``[x, y, w, h]`` object
                boxes (or None): windows touching them are never mined, so the
                labelled training frames themselves can serve as backgrounds.
            components: number of root filters K (clipped to the positives' count).
            window: patch side.
            stride: :meth:`score_map` step (and mining step on frames).
            config: HOG settings.
            regularization: SVM λ.
            mining_rounds: rescans of the negative pool after the first training.
            latent_rounds: re-assignments of positives to their best component.
            kmeans_restarts: k-means runs of the components' initialisation, the lowest inertia kept
                (:func:`kmeans`; 1 is the training before this option).
            initial_negatives: size of the first random negative cache.
            max_negative_cache: the cache never grows beyond this.
            mine_scales: pyramid factors of the background frames.
            mirror: add horizontally flipped positives.
            generator: the only randomness (k-means seeding, initial cache).
            verbose: print the cache size and training error per round.
            positive_weights: ``(P,)`` each positive's weight in the SVM's positive half
                (:func:`train_linear_svm`'s ``sample_weight``; its mirror copy weighs the same);
                None: all equal. The components' k-means and latent assignment do not use them.

        Returns:
            The trained detector.
        """
        generator = generator if generator is not None else torch.Generator().manual_seed(0)
        if components < 1:
            raise ValueError(f"components must be >= 1, got {components}")
        if mining_rounds < 0 or latent_rounds < 0:
            raise ValueError(f"mining_rounds and latent_rounds must be >= 0, got {mining_rounds}, {latent_rounds}")
        pos = to_float_patches(positives, window)
        neg = to_float_patches(negatives, window)
        if pos.shape[0] == 0:
            raise ValueError("positives is empty")
        if neg.shape[0] == 0 and not background_images:
            raise ValueError("need negatives or background_images, got neither")
        if ignore_boxes is not None and len(ignore_boxes) != len(background_images):
            raise ValueError(f"ignore_boxes must have one entry per background image ({len(background_images)}), got {len(ignore_boxes)}")
        pw = None
        if positive_weights is not None:
            pw = check_weights(positive_weights, pos.shape[0], flatten=True)
        if mirror:
            pos = torch.cat([pos, pos.flip(-1)])
            pw = None if pw is None else torch.cat([pw, pw])
        f_pos = _hog_chunked(pos, config)
        f_pool = _hog_chunked(neg, config)

        k = min(components, f_pos.shape[0])
        assign = kmeans(f_pos, k, generator=generator, restarts=kmeans_restarts)
        n_init = min(initial_negatives, f_pool.shape[0])
        cache = f_pool[torch.randperm(f_pool.shape[0], generator=generator)[:n_init]]
        if cache.shape[0] == 0:  # no patch pool: seed the cache from random frame windows
            cache = _random_frame_windows(background_images, window, config, n=initial_negatives, generator=generator)

        weights = torch.zeros(k, f_pos.shape[1])
        bias = torch.zeros(k)

        def train_all(warm: bool) -> None:
            for j in range(k):
                members = f_pos[assign == j]
                if members.shape[0] == 0:  # an emptied component keeps its previous filter
                    continue
                x = torch.cat([members, cache])
                y = torch.cat([torch.ones(members.shape[0]), -torch.ones(cache.shape[0])])
                init = (weights[j], bias[j]) if warm else None
                sw = None if pw is None else torch.cat([pw[assign == j], torch.ones(cache.shape[0], dtype=torch.float64)])
                weights[j], bias[j] = train_linear_svm(x, y, regularization=regularization, init=init, sample_weight=sw)

        train_all(warm=False)
        for round_ in range(max(mining_rounds, latent_rounds)):
            if round_ < latent_rounds and k > 1:
                assign = (f_pos @ weights.T + bias).argmax(1)
            if round_ < mining_rounds:
                cache = _mine(
                    cache, f_pool, weights, bias, background_images, ignore_boxes, window, stride, config, mine_scales, max_negative_cache
                )
            train_all(warm=True)
            if verbose:
                s_pos = (f_pos @ weights.T + bias).amax(1)
                s_neg = (cache @ weights.T + bias).amax(1)
                print(
                    f"round {round_ + 1}: cache {cache.shape[0]} negatives, "
                    f"pos error {(s_pos < 0).float().mean():.3f}, cache neg error {(s_neg > 0).float().mean():.3f}"
                )
        return cls(weights, bias, window=window, stride=stride, config=config)


def _random_frame_windows(
    images: Sequence[Tensor], window: int, config: HOGConfig, *, n: int, generator: torch.Generator
) -> Tensor:
    crops = []
    per_image = max(1, math.ceil(n / max(1, len(images))))
    for img in images:
        img = check_image(img)
        h, w = img.shape[-2:]
        if h < window or w < window:
            continue
        ys = torch.randint(0, h - window + 1, (per_image,), generator=generator)
        xs = torch.randint(0, w - window + 1, (per_image,), generator=generator)
        crops.extend(img[0, :, y : y + window, x : x + window] for y, x in zip(ys.tolist(), xs.tolist()))
    if not crops:
        raise ValueError(f"no background image is at least {window}x{window} pixels")
    return _hog_chunked(torch.stack(crops), config)


def _mine(
    cache: Tensor,
    pool: Tensor,
    weights: Tensor,
    bias: Tensor,
    images: Sequence[Tensor],
    ignore_boxes: Sequence[Tensor | None] | None,
    window: int,
    stride: int,
    config: HOGConfig,
    scales: Sequence[float],
    max_cache: int,
) -> Tensor:
    """DPM-style cache update: keep hard cached negatives, add margin violators from the pool."""
    from synthaug.detectors.sliding import resize_image

    def hard(f: Tensor) -> Tensor:
        return (f @ weights.T + bias).amax(1) > -1.0

    kept = cache[hard(cache)] if cache.shape[0] else cache
    new = [pool[hard(pool)]] if pool.shape[0] else []
    if images:
        detector = HOGDetector(weights, bias, window=window, stride=stride, config=config)
        for index, img in enumerate(images):
            img = check_image(img)
            ignore = None if ignore_boxes is None or ignore_boxes[index] is None else torch.as_tensor(ignore_boxes[index], dtype=torch.float32).reshape(-1, 4)
            for s in scales:
                level = resize_image(img, float(s))
                smap = detector.score_map(level)
                hard_windows = smap > -1.0
                if ignore is not None and ignore.shape[0]:
                    sy, sx = level.shape[-2] / img.shape[-2], level.shape[-1] / img.shape[-1]
                    y0 = torch.arange(smap.shape[0], dtype=torch.float32)[:, None, None] * stride / sy
                    x0 = torch.arange(smap.shape[1], dtype=torch.float32)[None, :, None] * stride / sx
                    overlaps = (
                        (x0 < ignore[:, 0] + ignore[:, 2])
                        & (x0 + window / sx > ignore[:, 0])
                        & (y0 < ignore[:, 1] + ignore[:, 3])
                        & (y0 + window / sy > ignore[:, 1])
                    ).any(-1)
                    hard_windows &= ~overlaps
                ys, xs = torch.nonzero(hard_windows, as_tuple=True)
                if ys.numel() == 0:
                    continue
                if ys.numel() > 500:  # the hardest windows of this level
                    top = torch.topk(smap[ys, xs], 500).indices
                    ys, xs = ys[top], xs[top]
                crops = torch.stack(
                    [level[0, :, y * stride : y * stride + window, x * stride : x * stride + window] for y, x in zip(ys.tolist(), xs.tolist())]
                )
                new.append(_hog_chunked(crops, config))
    merged = torch.cat([kept, *new]) if new else kept
    # the pool rows already in the cache come back as "new": deduplicate exactly
    merged = torch.unique(merged, dim=0)
    if merged.shape[0] > max_cache:
        order = (merged @ weights.T + bias).amax(1).argsort(descending=True)
        merged = merged[order[:max_cache]]
    if merged.shape[0] == 0:  # everything is easy: keep the old cache so the SVM still has negatives
        return cache
    return merged
