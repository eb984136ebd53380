"""Weak-learner distances d_WL^R (``wl_random``) and d_WL^L (``wl_learned``), eq. 5 of the paper.

    d_WL(X_re, X_sy) = sqrt(Σ_i α_i (h_i(X_re) - h_i(X_sy))²)

with h_i = h_{R_i, o_i, τ_i} the Levi–Weiss stumps of
:mod:`synthaug.detectors.weak_learners`:

- ``wl_random``: L random stumps, every α_i = 1;
- ``wl_learned``: the stumps and weights α_i that AdaBoost selects on the real
  seeds (a trained :class:`~synthaug.detectors.adaboost.AdaBoostDetector`, or
  positives/negatives to train one).

Both are piecewise constant in the image. ``wl_random_smooth`` and
``wl_learned_smooth`` (or ``temperature=T`` on either) replace the step
1[E > τ] by the sigmoid σ((E - τ) / T), which is differentiable in the image
(through the gradient magnitudes; orientation binning stays hard).

The learners' polarity (AdaBoost's ``E < τ`` stumps) does not change the
distance: 1 - h flips both terms of a difference.

Example:
    >>> import torch
    >>> d = get_distance_wl_random_example()
    >>> x = torch.rand(3, 1, 40, 40, generator=torch.Generator().manual_seed(1))
    >>> d(x[:1], x).shape, float(d(x, x).abs().max())
    (torch.Size([3]), 0.0)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import torch
from torch import Tensor

from synthaug.detectors.weak_learners import DEFAULT_EPS, WeakLearners
from synthaug.distances.registry import Distance, check_pair, register_distance

__all__ = [
    "WeakLearnerDistance",
    "SmoothWeakLearnerDistance",
    "wl_random",
    "wl_learned",
    "wl_random_smooth",
    "wl_learned_smooth",
]

DEFAULT_TEMPERATURE = 0.02
"""Sigmoid temperature of the smooth variants, in units of E (which lies in [0, 1])."""


class WeakLearnerDistance(Distance):
    """sqrt(Σ_i α_i (h_i(X_re) - h_i(X_sy))²) over a fixed set of weak learners.

    Args:
        learners: the stumps; ``learners.weights`` are the α_i (must be >= 0).
        temperature: None for the hard step (the paper); T > 0 for σ((E - τ) / T).

    Shape:
        - x_real: (B, 1, H, W) or (1, 1, H, W); x_syn: (B, 1, H, W), H = W = learners.window
        - output: (B,)
    """

    differentiable = False

    def __init__(self, learners: WeakLearners, temperature: float | None = None) -> None:
        super().__init__()
        if not isinstance(learners, WeakLearners) or len(learners) == 0:
            raise ValueError(f"learners must be a non-empty WeakLearners, got {learners!r}")
        if (learners.weights < 0).any():
            raise ValueError(f"weak learner weights must be >= 0, got min {float(learners.weights.min())}")
        if temperature is not None and not temperature > 0:
            raise ValueError(f"temperature must be > 0 or None, got {temperature}")
        self.learners = learners
        self.temperature = temperature
        self.register_buffer("sqrt_weights", learners.weights.float().sqrt(), persistent=False)

    def features(self, x: Tensor) -> Tensor:
        w = self.learners.window
        if x.shape[1] != 1 or x.shape[-2:] != (w, w):
            raise ValueError(f"weak-learner distances take (B, 1, {w}, {w}) patches, got {tuple(x.shape)}")
        h = self.learners.responses(x, self.temperature)
        return h * self.sqrt_weights.to(h.dtype)

    def forward(self, x_real: Tensor, x_syn: Tensor) -> Tensor:
        x_real, x_syn = check_pair(x_real, x_syn)
        return self.compare(self.features(x_real), self.features(x_syn))

    def extra_repr(self) -> str:
        return f"name={self.name!r}, learners={len(self.learners)}, temperature={self.temperature}"


class SmoothWeakLearnerDistance(WeakLearnerDistance):
    """:class:`WeakLearnerDistance` with the sigmoid step (differentiable)."""

    differentiable = True

    def __init__(self, learners: WeakLearners, temperature: float = DEFAULT_TEMPERATURE) -> None:
        if temperature is None:
            raise ValueError("SmoothWeakLearnerDistance needs a temperature > 0, got None")
        super().__init__(learners, temperature)


def _distance(learners: WeakLearners, temperature: float | None, name: str) -> WeakLearnerDistance:
    d = WeakLearnerDistance(learners) if temperature is None else SmoothWeakLearnerDistance(learners, temperature)
    d.name = name  # instance attribute: one class serves the four registry names
    return d


def _random_learners(n_learners: int, window: int, n_bins: int, seed: int,
                     reference: Tensor | None, min_size: int, eps: float) -> WeakLearners:
    if not isinstance(n_learners, int) or n_learners < 1:
        raise ValueError(f"n_learners must be an int >= 1, got {n_learners}")
    return WeakLearners.random(n_learners, window, n_bins, generator=torch.Generator().manual_seed(seed),
                               reference=reference, min_size=min_size, eps=eps)


def _learned_learners(
    detector: Any,
    positives: Tensor | None,
    negatives: Tensor | None,
    checkpoint: str | Path | None,
    n_rounds: int,
    candidates: int | str,
    seed: int,
) -> WeakLearners:
    from synthaug.detectors.adaboost import AdaBoostDetector, train_adaboost

    given = [detector is not None, checkpoint is not None, positives is not None or negatives is not None]
    if sum(given) != 1:
        raise ValueError("wl_learned needs exactly one of detector=, checkpoint= or positives= and negatives=, "
                         f"got detector={detector is not None}, checkpoint={checkpoint!r}, "
                         f"positives/negatives={positives is not None}/{negatives is not None}")
    if checkpoint is not None:
        from synthaug.detectors.base import load_detector

        detector = load_detector(checkpoint)
    if detector is not None:
        if isinstance(detector, WeakLearners):
            return detector
        if not isinstance(detector, AdaBoostDetector):
            raise ValueError(f"detector must be an AdaBoostDetector or WeakLearners, got {type(detector).__name__}")
        return detector.learners
    if positives is None or negatives is None:
        raise ValueError("wl_learned needs both positives= and negatives= to run AdaBoost on the seeds")
    return train_adaboost(positives, negatives, n_rounds, candidates=candidates, seed=seed).learners


def _example_random_any(generator: torch.Generator) -> WeakLearnerDistance:
    return _example_random(generator)


@register_distance("wl_random", example=_example_random_any,
                   doc="random Levi-Weiss weak learners, weight 1 (d_WL^R, eq. 5)")
def wl_random(
    n_learners: int = 1000,
    window: int = 40,
    n_bins: int = 4,
    seed: int = 0,
    reference: Tensor | None = None,
    min_size: int = 4,
    eps: float = DEFAULT_EPS,
    temperature: float | None = None,
) -> WeakLearnerDistance:
    """d_WL^R: L random weak learners h_{R,o,τ}, every α = 1 (eq. 5).

    Args:
        n_learners: L.
        window: patch side.
        n_bins: orientation bins K.
        seed: seeds the draw of (R, o, τ).
        reference: optional real patches ``(N, 1, window, window)``; each τ is then
            the energy E of a random reference patch (learners that split real
            data), otherwise τ ~ U(0, 2 / K) (E averages 1 / K on isotropic texture).
        min_size: smallest rectangle side.
        eps: ε of the energy normalisation.
        temperature: None (hard step, the paper) or T for the sigmoid variant.
    """
    return _distance(_random_learners(n_learners, window, n_bins, seed, reference, min_size, eps),
                     temperature, "wl_random" if temperature is None else "wl_random_smooth")


def _example_learned(generator: torch.Generator, temperature: float | None = None) -> WeakLearnerDistance:
    from synthaug.detectors.toy import toy_patches

    seed = int(torch.randint(0, 2**31 - 1, (1,), generator=generator))
    pos, neg = toy_patches(60, 60, seed=seed)
    return wl_learned(positives=pos, negatives=neg, n_rounds=60, candidates=1500, seed=seed, temperature=temperature)


@register_distance("wl_learned", needs_fit=True, example=_example_learned,
                   doc="weak learners and weights selected by AdaBoost on the seeds (d_WL^L, eq. 5)")
def wl_learned(
    detector: Any = None,
    positives: Tensor | None = None,
    negatives: Tensor | None = None,
    checkpoint: str | Path | None = None,
    n_rounds: int = 100,
    candidates: int | str = "exhaustive",
    seed: int = 0,
    temperature: float | None = None,
) -> WeakLearnerDistance:
    """d_WL^L: the weak learners and weights α AdaBoost selects on the real seeds (eq. 5).

    Give exactly one source of learners:

    Args:
        detector: a trained :class:`~synthaug.detectors.adaboost.AdaBoostDetector`
            (or a :class:`~synthaug.detectors.weak_learners.WeakLearners`).
        positives: real seed patches ``(P, 1, 40, 40)``, with ``negatives``:
            AdaBoost is trained on them here.
        negatives: background patches ``(N, 1, 40, 40)``.
        checkpoint: path of a saved AdaBoost detector (``save_detector``).
        n_rounds: AdaBoost rounds when training here.
        candidates: candidate features when training here (see ``train_adaboost``).
        seed: seed of random candidates when training here.
        temperature: None (hard step, the paper) or T for the sigmoid variant.
    """
    learners = _learned_learners(detector, positives, negatives, checkpoint, n_rounds, candidates, seed)
    return _distance(learners, temperature, "wl_learned" if temperature is None else "wl_learned_smooth")


def _example_random(generator: torch.Generator, temperature: float | None = None) -> WeakLearnerDistance:
    from synthaug.detectors.toy import toy_patches

    seed = int(torch.randint(0, 2**31 - 1, (1,), generator=generator))
    pos, neg = toy_patches(30, 30, seed=seed)
    return wl_random(seed=seed, reference=torch.cat([pos, neg]), temperature=temperature)


def get_distance_wl_random_example() -> WeakLearnerDistance:
    """A ``wl_random`` distance whose thresholds come from generated patches (for docs and tests)."""
    return _example_random(torch.Generator().manual_seed(0))


@register_distance("wl_random_smooth", example=lambda g: _example_random(g, DEFAULT_TEMPERATURE),
                   doc="wl_random with the step replaced by a sigmoid of (E - tau) / T (differentiable)")
def wl_random_smooth(temperature: float = DEFAULT_TEMPERATURE, **kwargs: Any) -> WeakLearnerDistance:
    """``wl_random`` with σ((E - τ) / T) instead of 1[E > τ]; other arguments as :func:`wl_random`."""
    return wl_random(temperature=temperature, **kwargs)


@register_distance("wl_learned_smooth", needs_fit=True,
                   example=lambda g: _example_learned(g, DEFAULT_TEMPERATURE),
                   doc="wl_learned with the step replaced by a sigmoid of (E - tau) / T (differentiable)")
def wl_learned_smooth(temperature: float = DEFAULT_TEMPERATURE, **kwargs: Any) -> WeakLearnerDistance:
    """``wl_learned`` with σ((E - τ) / T) instead of 1[E > τ]; other arguments as :func:`wl_learned`."""
    return wl_learned(temperature=temperature, **kwargs)
