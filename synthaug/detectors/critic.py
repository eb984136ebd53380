"""A realism critic in a detector's features: which synthetic patches look synthetic to a linear classifier.

The paper fits the capture parameters so that each seed's render is close to the real seed *in the detector's
features*; the random poses drawn afterwards are not checked. :func:`realism_scores` checks them: an L2 logistic
regression (:func:`fit_logistic`) trained to tell the seed set's real patches from synthetic ones in HOG features
(or in the edge-orientation energies AdaBoost's stumps threshold, :func:`weak_learner_features`) gives every
synthetic patch a "looks synthetic" logit, cross-fitted by seed (a patch is scored by a critic that never
saw its own seed, real or synthetic), and :func:`least_synthetic` keeps the patches the critic finds least synthetic
(discriminator rejection sampling, Azadi et al., ICLR 2019, with a linear critic).

:func:`fit_logistic` is also the classifier of the two-sample test
(:func:`synthaug.diagnose.gap.classifier_two_sample_test`); it lives here, upstream of the diagnosis, so that the
training sets can use it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from torch import Tensor

from synthaug._checks import one_of

__all__ = ["REALISM_FEATURES", "REALISM_SELECTION", "RealismCritic", "check_realism_features",
           "check_realism_selection", "fit_logistic", "hog_features", "least_synthetic", "realism_scores",
           "realism_variants", "seed_quotas", "standardiser", "weak_learner_features"]

REALISM_FEATURES = ("hog", "weak_learners")
"""The features a critic of :func:`realism_scores` sees: ``"hog"`` (the HOG descriptor, :func:`hog_features`; the
default) or ``"weak_learners"`` (the edge-orientation energies of random Levi–Weiss rectangles, the features AdaBoost's
stumps threshold, at AdaBoost's energy floor: :func:`weak_learner_features`)."""

REALISM_SELECTION = ("seed", "set", "item")
"""How a critic picks the synthetic positives (:func:`~synthaug.detectors.training_sets.synthetic_positives`):
``"seed"`` (the default since stop 83: every seed keeps its share of its own draws, the least synthetic of them, so the
critic picks poses within a seed and never drops a seed), ``"set"`` (the ``count`` least synthetic of the whole draw,
stop 82's: a seed whose renders all look synthetic may keep none; these two are :func:`least_synthetic`'s) or
``"item"`` (the lazy form, as :class:`~synthaug.data.synthetic.SyntheticObjectDataset` with a ``realism_critic``
draws: each patch the least synthetic of its own candidates, which keep its seed)."""


def check_realism_selection(selection: Any, name: str = "realism_selection") -> str:
    """``selection`` if it is one of :data:`REALISM_SELECTION`, else ``ValueError`` naming ``name``.

    >>> check_realism_selection("seed")
    'seed'
    """
    return one_of(selection, REALISM_SELECTION, name)


def check_realism_features(features: Any, name: str = "realism_features", selection: str | None = None) -> str:
    """``features`` if it is one of :data:`REALISM_FEATURES`, else ``ValueError`` naming ``name``; with a
    ``selection``, also refused where it is ``"item"`` and the features are not HOG's (the lazy selection scores with
    the dataset's :class:`RealismCritic`, which is in HOG features).

    >>> check_realism_features("weak_learners", selection="seed")
    'weak_learners'
    """
    one_of(features, REALISM_FEATURES, name)
    if features != "hog" and selection == "item":
        raise ValueError(f"realism_selection 'item' scores candidates in HOG features (the dataset's RealismCritic); "
                         f"{name} {features!r} takes 'seed' or 'set'")
    return features


def realism_variants(keeps: Any, selections: Any) -> list[tuple[float, str]]:
    """Each distinct ``(realism_keep, realism_selection)`` of ``keeps`` × ``selections``, in order. A keep of 1 selects
    nothing, so it comes once, as ``"set"`` (the selection every-draw cells are keyed under).

    >>> realism_variants([1.0, 0.25], ["seed", "set"])
    [(1.0, 'set'), (0.25, 'seed'), (0.25, 'set')]
    """
    return list(dict.fromkeys((k, "set" if k == 1 else check_realism_selection(s)) for k in keeps for s in selections))


def fit_logistic(x: np.ndarray, y: np.ndarray, *, C: float = 1.0, max_iter: int = 100,
                 tol: float = 1e-9) -> tuple[np.ndarray, float]:
    """L2-penalised logistic regression, ``min Σ_i log(1 + exp(-s_i (x_i·w + b))) + ||w||² / (2C)``.

    The objective of scikit-learn's ``LogisticRegression(C=C)`` (intercept not penalised); scikit-learn is
    not a dependency of synthaug. Minimised by Newton's method with a backtracking line search, from zero —
    deterministic, and quadratic convergence also when the classes are (nearly) separable, where first-order
    methods crawl. With more features than samples (HOG, CNN activations of a seed set), the problem is
    solved exactly in the span of the samples: the optimum satisfies ``w = -C Xᵀ(σ(z) - y)``, so with
    ``Xᵀ = Q R`` (thin QR) ``w = Q β`` and ``x_i·w = (Rᵀ β)_i``, an n-dimensional problem with the same
    penalty ``||β||²``.

    Args:
        x: features ``(N, D)`` (standardise them first: the penalty is isotropic).
        y: labels in {0, 1}, ``(N,)``.
        C: inverse penalty strength.
        max_iter: Newton iterations.
        tol: stop when the gradient's largest entry is below ``tol`` times ``N``.

    Returns:
        ``(w, b)``: weights ``(D,)`` and intercept; P(y = 1 | x) = σ(x·w + b).

    Example:
        >>> w, b = fit_logistic(np.array([[-1.0], [1.0]]), np.array([0, 1]))
        >>> round(float(w[0]), 3), abs(round(b, 6))  # the optimum solves w = 2 σ(-w)
        (0.675, 0.0)
    """
    from scipy.special import expit

    if not C > 0:
        raise ValueError(f"C must be > 0, got {C}")
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    n, d = x.shape
    if x.shape[0] != y.shape[0]:
        raise ValueError(f"x and y must have the same number of rows, got {x.shape[0]} and {y.shape[0]}")
    q = None
    if d > n:
        q, r = np.linalg.qr(x.T)  # (D, N), (N, N)
        z_feats = r.T
    else:
        z_feats = x
    k = z_feats.shape[1]
    design = np.concatenate([z_feats, np.ones((n, 1))], axis=1)
    penalty = np.full(k + 1, 1.0 / C)
    penalty[k] = 0.0

    def objective(theta: np.ndarray) -> float:
        z = design @ theta
        return float(np.sum(np.logaddexp(0.0, z) - y * z) + 0.5 * np.sum(penalty * theta * theta))

    theta = np.zeros(k + 1)
    f = objective(theta)
    for _ in range(max_iter):
        p = expit(design @ theta)
        grad = design.T @ (p - y) + penalty * theta
        if np.abs(grad).max() < tol * n:
            break
        hess = (design * (p * (1 - p))[:, None]).T @ design
        hess[np.diag_indices_from(hess)] += penalty + 1e-12
        step = np.linalg.solve(hess, grad)
        t, slope = 1.0, float(grad @ step)
        while True:  # Armijo backtracking: a full Newton step can overshoot far from the optimum
            candidate = theta - t * step
            f_new = objective(candidate)
            if f_new <= f - 1e-4 * t * slope or t < 1e-10:
                break
            t *= 0.5
        theta, f = candidate, f_new
    w = theta[:k] if q is None else q @ theta[:k]
    return w.copy(), float(theta[k])


def standardiser(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Column means and standard deviations of ``x`` for ``(x - mean) / std``; a constant column's std is 1, so it
    stays constant (0) instead of NaN. The critic's and the two-sample test's standardisation."""
    mu = x.mean(0)
    sd = x.std(0)
    return mu, np.where(sd > 1e-12, sd, 1.0)  # constant features stay constant (0), not NaN


def hog_features(patches: Tensor | np.ndarray, config: Any = None) -> np.ndarray:
    """HOG descriptors (:func:`~synthaug.detectors.hog.hog`, the detector's default settings unless ``config``) of
    grayscale patches: uint8 ``(N, P, P)`` as a seed set stores them, or float ``(N, 1, P, P)`` in [0, 1].

    Returns:
        float64 ``(N, D)``.
    """
    from synthaug.detectors.hog import DEFAULT_HOG, hog

    x = _float_patches(patches)
    with torch.no_grad():
        return torch.cat([hog(c, config or DEFAULT_HOG) for c in x.split(1024)]).double().numpy()


def _float_patches(patches: Tensor | np.ndarray) -> Tensor:
    """uint8 ``(N, P, P)`` or float ``(N, 1, P, P)`` patches, numpy or torch, as float32 ``(N, 1, P, P)`` in [0, 1]
    (:func:`~synthaug.detectors.base.to_float_patches`, which names a wrong type or shape)."""
    from synthaug.detectors.base import to_float_patches

    x = torch.from_numpy(np.ascontiguousarray(patches)) if isinstance(patches, np.ndarray) else patches
    return to_float_patches(x, int(x.shape[-1]) if isinstance(x, Tensor) and x.dim() else 0)


def weak_learner_features(patches: Tensor | np.ndarray, reference: Tensor | np.ndarray, *, n: int = 2000,
                          seed: int = 0, floor: float = 1.0, n_bins: int = 4) -> np.ndarray:
    """The edge-orientation energies ``E(X, R, o)`` of ``n`` random Levi–Weiss rectangles (the features AdaBoost's
    stumps threshold, :func:`~synthaug.detectors.weak_learners.edge_orientation_energy`), at AdaBoost's energy floor.

    Args:
        patches: grayscale patches, uint8 ``(M, P, P)`` or float ``(M, 1, P, P)`` in [0, 1].
        reference: the real patches (same formats); the floor's unit is their gradient level
            (:func:`~synthaug.detectors.adaboost.gradient_level`), as AdaBoost's is its negatives'.
        n: rectangles, drawn with ``seed`` (:func:`~synthaug.detectors.weak_learners.random_candidates`, sides >= 4).
        seed: seeds the rectangles (the same rectangles for every call with the same ``seed`` and patch size).
        floor: the energy floor per pixel in units of the reference's gradient level (AdaBoost's default,
            ``TrainOptions.ada_energy_floor``, is 1; 0: the paper's E).
        n_bins: orientation bins K.

    Returns:
        float64 ``(M, n)``, in [0, 1).
    """
    from synthaug.detectors.adaboost import gradient_level
    from synthaug.detectors.weak_learners import DEFAULT_EPS, edge_orientation_energy, random_candidates

    x, ref = _float_patches(patches).double(), _float_patches(reference).double()
    if x.shape[-2:] != ref.shape[-2:]:
        raise ValueError(f"patches and reference must have the same size, got {tuple(x.shape[-2:])} and "
                         f"{tuple(ref.shape[-2:])}")
    if not (isinstance(n, int) and n >= 1):
        raise ValueError(f"n must be an int >= 1, got {n!r}")
    rects, orients = random_candidates(n, int(x.shape[-1]), n_bins, generator=torch.Generator().manual_seed(seed))
    level = float(floor) * gradient_level(ref) if floor else 0.0
    with torch.no_grad():
        return torch.cat([edge_orientation_energy(c, rects, orients, n_bins, DEFAULT_EPS, level)
                          for c in x.split(1024)]).numpy()


@dataclass(frozen=True, eq=False)
class RealismCritic:
    """A cross-fitted realism critic of a seed set, as a picklable callable ``critic(patches, seed_index) -> logits``.

    :meth:`fit` splits the seeds into ``folds`` parts and trains one L2 logistic regression per part on the *other*
    parts' seeds (real 0, synthetic 1, in HOG features); a patch drawn with seed ``s`` is scored by the part that never
    saw ``s``. Holds numpy arrays only, so a :class:`~synthaug.data.synthetic.SyntheticObjectDataset` can take it as
    its ``realism_critic`` into DataLoader workers (its best of ``realism_candidates`` draws per item).

    Attributes:
        part: ``(N,)`` int, the part of each seed.
        mean, std: ``(folds, D)``, each part's standardiser.
        weight: ``(folds, D)``, each part's weights; bias: ``(folds,)``.
        hog_config: the HOG settings of the features (None: the detector's defaults).

    Example:
        >>> critic = RealismCritic.fit(seedset.patches, synthetic, groups)  # doctest: +SKIP
        >>> critic(synthetic[:4], groups[:4])  # doctest: +SKIP
        array([ 0.41, -1.2 ,  0.07,  2.3 ])
    """

    part: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    weight: np.ndarray
    bias: np.ndarray
    hog_config: Any = None

    @classmethod
    def fit(
        cls,
        real: Tensor | np.ndarray,
        synthetic: Tensor | np.ndarray,
        groups: np.ndarray,
        *,
        folds: int = 2,
        synthetic_per_real: int = 5,
        C: float = 1.0,
        seed: int = 0,
        hog_config: Any = None,
    ) -> RealismCritic:
        """The critic of real seeds ``real`` against ``synthetic`` patches drawn with seeds ``groups``.

        Args:
            real: the seed set's real patches, ``(N, P, P)`` uint8 or ``(N, 1, P, P)`` float in [0, 1]; seed ``i`` is
                row i.
            synthetic: synthetic patches, same formats.
            groups: ``(M,)`` int, the seed each synthetic patch was drawn with (its capture parameters), in
                ``[0, N)``.
            folds: parts of the seeds (>= 2, <= N).
            synthetic_per_real: cap on each part's synthetic training rows, per real training row (drawn without
                replacement).
            C: inverse L2 penalty.
            seed: seeds the parts and the subsample (``numpy.random.default_rng``).
            hog_config: HOG settings (None: the detector's defaults).
        """
        return cls.from_features(hog_features(real, hog_config), hog_features(synthetic, hog_config), groups,
                                 folds=folds, synthetic_per_real=synthetic_per_real, C=C, seed=seed,
                                 hog_config=hog_config)

    @classmethod
    def from_dataset(
        cls,
        dataset: Any,
        real: Tensor | np.ndarray,
        count: int | None = None,
        *,
        epoch: int = 0,
        batch: int = 256,
        folds: int = 2,
        synthetic_per_real: int = 5,
        C: float = 1.0,
        seed: int = 0,
        hog_config: Any = None,
    ) -> RealismCritic:
        """:meth:`fit` on ``count`` synthetic object draws of ``dataset`` (a
        :class:`~synthaug.data.synthetic.SyntheticObjectDataset` in patch mode, without a critic yet): its items
        from ``epoch`` on in index order, negatives skipped, as rendered before its ``transforms`` (what the
        dataset's critic scores). Then ``dataset.realism_critic = critic`` makes each item the least synthetic of
        its candidates.

        Args:
            real: the real patches of the dataset's seeds, one per seed in its order (e.g. ``seedset.patches``).
            count: synthetic draws (default ``2 · synthetic_per_real · len(real)``, so that each part's cap is
                reached).
            epoch: the dataset's epoch the draws start in (further epochs when its synthetic items are fewer).
            batch: items rendered together.
            folds, synthetic_per_real, C, seed, hog_config: as in :meth:`fit`.

        Example:
            >>> ds = SyntheticObjectDataset("quadcopter", seedset, params="fit.pt", length=10_000)  # doctest: +SKIP
            >>> ds.realism_critic = RealismCritic.from_dataset(ds, seedset.patches)  # doctest: +SKIP
        """
        if getattr(dataset, "realism_critic", None) is not None:
            raise ValueError("the dataset already has a realism_critic: draw the critic's training patches from the "
                             "dataset without one (set dataset.realism_critic = None first)")
        if getattr(dataset, "mode", None) != "patch":
            raise ValueError("a realism critic scores object patches: give a dataset in patch mode")
        n_real, total = int(dataset.n_real), len(dataset)
        if total == n_real or float(dataset.negative_fraction) >= 1:
            raise ValueError("the dataset draws no synthetic object (no synthetic items, or negative_fraction 1)")
        count = 2 * synthetic_per_real * len(real) if count is None else count
        if not (isinstance(count, (int, np.integer)) and count >= 1):
            raise ValueError(f"count must be an int >= 1, got {count!r}")
        drawn, index, ep = [], n_real, int(epoch)
        while len(drawn) < count:
            if index == total:  # the next epoch's draws
                index, ep = n_real, ep + 1
            p = dataset.make_params(index, ep)
            if not p.negative:
                drawn.append(p)
            index += 1
        patches, groups = [], []
        for start in range(0, count, batch):
            items = dataset.render(drawn[start:start + batch], transformed=False)
            patches.append(torch.stack([img for img, _ in items]).float().clamp(0, 1))
            groups += [int(t["seed_index"]) for _, t in items]
        return cls.fit(real, _gray(torch.cat(patches)), np.asarray(groups, np.int64), folds=folds,
                       synthetic_per_real=synthetic_per_real, C=C, seed=seed, hog_config=hog_config)

    @classmethod
    def from_features(cls, real: np.ndarray, synthetic: np.ndarray, groups: np.ndarray, *, folds: int = 2,
                      synthetic_per_real: int = 5, C: float = 1.0, seed: int = 0,
                      hog_config: Any = None) -> RealismCritic:
        """:meth:`fit` on HOG features already computed (:func:`hog_features` with ``hog_config``): ``real``
        ``(N, D)``, ``synthetic`` ``(M, D)``."""
        fr, fs = real, synthetic
        n, m = len(fr), len(fs)
        groups = _check_groups(groups, m, n)
        if not (isinstance(folds, int) and 2 <= folds <= n):
            raise ValueError(f"folds must be an int in [2, number of real seeds = {n}], got {folds!r}: the critic "
                             f"of each part is trained on the other parts' seeds")
        if not (isinstance(synthetic_per_real, int) and synthetic_per_real >= 1):
            raise ValueError(f"synthetic_per_real must be an int >= 1, got {synthetic_per_real!r}")
        rng = np.random.default_rng(seed)
        part = np.empty(n, np.int64)
        for j, idx in enumerate(np.array_split(rng.permutation(n), folds)):
            part[idx] = j
        mean, std, weight, bias = [], [], [], []
        for j in range(folds):
            train_real, train_syn = np.flatnonzero(part != j), np.flatnonzero(part[groups] != j)
            if len(train_syn) == 0:
                raise ValueError(f"no synthetic patch was drawn with the seeds outside part {j}: draw more patches")
            cap = synthetic_per_real * len(train_real)
            if len(train_syn) > cap:
                train_syn = np.sort(rng.choice(train_syn, cap, replace=False))
            x = np.concatenate([fr[train_real], fs[train_syn]])
            y = np.r_[np.zeros(len(train_real)), np.ones(len(train_syn))]
            mu, sd = standardiser(x)
            w, b = fit_logistic((x - mu) / sd, y, C=C)
            mean.append(mu)
            std.append(sd)
            weight.append(w)
            bias.append(b)
        return cls(part, np.stack(mean), np.stack(std), np.stack(weight), np.asarray(bias), hog_config)

    @property
    def n_seeds(self) -> int:
        """The number of seeds the critic was fitted on."""
        return len(self.part)

    def score_features(self, features: np.ndarray, seed_index: np.ndarray) -> np.ndarray:
        """The logits of HOG ``features`` ``(M, D)`` (:func:`hog_features` with ``hog_config``) drawn with seeds
        ``seed_index`` ``(M,)``, each by the part that never saw its seed."""
        seed_index = _check_groups(seed_index, len(features), self.n_seeds)
        out = np.zeros(len(features))
        for j in range(len(self.bias)):
            mine = self.part[seed_index] == j
            out[mine] = ((features[mine] - self.mean[j]) / self.std[j]) @ self.weight[j] + self.bias[j]
        return out

    def __call__(self, patches: Tensor | np.ndarray, seed_index: Tensor | np.ndarray) -> np.ndarray:
        """The "looks synthetic" logit (higher: more synthetic) of each patch, float64 ``(M,)``.

        Args:
            patches: ``(M, P, P)`` uint8 or ``(M, C, P, P)`` float in [0, 1]; a colour patch (C = 3) is scored in
                gray (ITU-R BT.601 luma, as OpenCV's RGB2GRAY and the real items' conversion).
            seed_index: ``(M,)`` int, the seed each patch was drawn with.
        """
        return self.score_features(hog_features(_gray(patches), self.hog_config), np.asarray(seed_index))


def _gray(patches: Tensor | np.ndarray) -> Tensor | np.ndarray:
    """Colour float patches ``(M, 3, P, P)`` in gray (kornia's ITU-R 601 luma); anything else as it is."""
    if isinstance(patches, Tensor) and patches.dim() == 4 and patches.shape[1] == 3:
        import kornia

        return kornia.color.rgb_to_grayscale(patches.float())
    return patches


def _check_groups(groups: Any, m: int, n: int) -> np.ndarray:
    """``groups`` as an ``(m,)`` int array in ``[0, n)`` (the seed of each synthetic patch), else ``ValueError``."""
    groups = np.asarray(groups)
    if groups.shape != (m,) or not (m == 0 or np.issubdtype(groups.dtype, np.integer)):
        raise ValueError(f"groups must be ({m},) integers (the seed of each synthetic patch), got "
                         f"{groups.dtype} {groups.shape}")
    if m and (groups.min() < 0 or groups.max() >= n):
        raise ValueError(f"groups must lie in [0, {n}) (one real patch per seed), got [{groups.min()}, {groups.max()}]")
    return groups.astype(np.int64)


def realism_scores(
    real: Tensor | np.ndarray,
    synthetic: Tensor | np.ndarray,
    groups: np.ndarray,
    *,
    folds: int = 2,
    synthetic_per_real: int = 5,
    C: float = 1.0,
    seed: int = 0,
    features: str = "hog",
) -> np.ndarray:
    """Cross-fitted "looks synthetic" logit of every synthetic patch, in HOG features (or AdaBoost's).

    The real seeds are split at random into ``folds`` parts. For each part, a logistic regression (:func:`fit_logistic`,
    features standardised on its training rows) learns real (0) vs synthetic (1) from the *other* parts' real seeds
    and the synthetic patches drawn with those seeds (at most ``synthetic_per_real`` per real seed, drawn without
    replacement), and scores the synthetic patches of its own part. So no patch is scored by a critic that saw its
    seed: a seed's background or fitted render cannot make its own patches look real. (:meth:`RealismCritic.fit` on
    the same patches, scoring them.)

    Args:
        real: the seed set's real patches, ``(N, P, P)`` uint8 or ``(N, 1, P, P)`` float in [0, 1]; seed ``i`` is row i.
        synthetic: synthetic patches, same formats.
        groups: ``(M,)`` int, the seed each synthetic patch was drawn with (its capture parameters), in ``[0, N)``.
        folds: parts of the seeds (>= 2, <= N).
        synthetic_per_real: cap on the synthetic training rows, per real training row.
        C: inverse L2 penalty.
        seed: seeds the parts and the subsample (``numpy.random.default_rng``), and the rectangles of
            ``"weak_learners"`` features.
        features: what the critic sees (:data:`REALISM_FEATURES`): ``"hog"`` (:func:`hog_features`) or
            ``"weak_learners"`` (:func:`weak_learner_features` at its defaults, the floor's unit the real patches'
            gradient level).

    Returns:
        float64 ``(M,)``: the critic's logit ``x·w + b`` of each synthetic patch (higher: looks more synthetic).
    """
    if check_realism_features(features, "features") == "weak_learners":
        fr, fs = weak_learner_features(real, real, seed=seed), weak_learner_features(synthetic, real, seed=seed)
    else:
        fr, fs = hog_features(real), hog_features(synthetic)
    critic = RealismCritic.from_features(fr, fs, groups, folds=folds,
                                         synthetic_per_real=synthetic_per_real, C=C, seed=seed)
    return critic.score_features(fs, groups)


def seed_quotas(groups: np.ndarray, count: int) -> np.ndarray:
    """How many of each seed's drawn patches to keep so that ``count`` are kept in all, every seed the same share of
    its own draws: ``count · drawn_s / drawn`` rounded by largest remainders (ties: the lower seed), so the quotas
    sum to ``count`` and never exceed a seed's draws.

    Args:
        groups: ``(M,)`` int >= 0, the seed of each drawn patch.
        count: patches kept in all, in ``[0, M]``.

    Returns:
        int64 ``(max(groups) + 1,)``: the quota of each seed (0 for a seed that drew nothing).

    Example:
        >>> seed_quotas(np.array([0, 0, 0, 1, 1, 2, 2, 2, 2, 2]), 5).tolist()  # exact shares 1.5, 1, 2.5
        [2, 1, 2]
    """
    groups = np.asarray(groups)
    m = len(groups)
    if not (isinstance(count, (int, np.integer)) and 0 <= count <= m):
        raise ValueError(f"count must be an int in [0, {m}], got {count!r}")
    drawn = np.bincount(groups, minlength=int(groups.max()) + 1 if m else 0).astype(np.int64)
    scaled = drawn * int(count)  # the exact shares are scaled / m: integer arithmetic, so equal remainders are equal
    quota, remainder = scaled // max(m, 1), scaled % max(m, 1)
    short = int(count) - int(quota.sum())
    if short > 0:  # largest remainders first; a stable sort keeps the lower seed first among equal remainders
        quota[np.argsort(-remainder, kind="stable")[:short]] += 1
    return quota


def least_synthetic(
    real: Tensor | np.ndarray,
    synthetic: Tensor | np.ndarray,
    groups: np.ndarray,
    count: int,
    *,
    selection: str = "seed",
    **kwargs: Any,
) -> np.ndarray:
    """Indices of the ``count`` synthetic patches :func:`realism_scores` finds least synthetic, in their drawn order.

    Ties keep the earlier patch. ``kwargs`` go to :func:`realism_scores`.

    Args:
        selection: ``"seed"`` (the default): each seed keeps its :func:`seed_quotas` share of its own draws, its
            lowest logits; ``"set"``: the ``count`` lowest logits of the whole draw (a seed whose renders all look
            synthetic may keep none; :data:`REALISM_SELECTION`).

    Returns:
        int64 ``(count,)``, increasing.
    """
    m = len(synthetic)
    if not (isinstance(count, (int, np.integer)) and 0 <= count <= m):
        raise ValueError(f"count must be an int in [0, {m}], got {count!r}")
    if check_realism_selection(selection, "selection") == "item":
        raise ValueError("least_synthetic picks from a drawn pool ('seed' or 'set'); 'item' picks among each item's "
                         "own candidates, as SyntheticObjectDataset does with a realism_critic")
    scores = realism_scores(real, synthetic, groups, **kwargs)
    if selection == "set":
        return np.sort(np.argsort(scores, kind="stable")[:count]).astype(np.int64)
    groups = np.asarray(groups)
    keep = [np.zeros(0, np.int64)]
    for g, quota in enumerate(seed_quotas(groups, count)):  # each seed's own lowest logits
        idx = np.flatnonzero(groups == g)
        keep.append(idx[np.argsort(scores[idx], kind="stable")[:quota]])
    return np.sort(np.concatenate(keep)).astype(np.int64)
