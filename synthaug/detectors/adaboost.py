"""Discrete AdaBoost over Levi–Weiss decision stumps, with a soft attentional cascade.

The paper's second detector family (Rozantsev et al., sec. 4): an AdaBoost
classifier (Freund & Schapire) whose weak learners are the edge-orientation
stumps h_{R,o,τ} of :mod:`synthaug.detectors.weak_learners`. The strong
classifier scores a patch by

    F(X) = Σ_t α_t (2 h_t(X) - 1),      object when F(X) > 0.

Training is plain discrete AdaBoost with class-balanced initial weights; every
round searches all candidate (R, o) features and all thresholds at once (one
presort of the feature matrix, then weighted cumulative sums per round).

For speed, :meth:`AdaBoostDetector.score_map` can run as a *soft cascade*
(Bourdev & Brandt 2005): after every ``stage_size`` stumps the windows whose
partial score is below the lowest partial score of the training positives
(minus a margin, see :meth:`AdaBoostDetector.calibrate_cascade`) are dropped.
A dropped window gets the lowest final score it could still reach (partial
score minus the remaining Σ α), so its score stays a lower bound of the exact
one and below every window that survived with the same partial sum.

Dense scoring evaluates every stump at every window from one set of
orientation integral images per pyramid level (block-summed when the
rectangles and the stride share a grid, see :meth:`AdaBoostDetector._grid`):
while most windows are alive, each stump's margin is computed over the whole
window grid at once from shifted views of its response map (no gathers); once
the cascade has dropped most windows, only the survivors' corners are gathered.
``AdaBoostDetector._score_map_reference`` keeps the former implementation
(stage-wise gathers), against which the tests check the scores.

Example:
    >>> from synthaug.detectors.toy import toy_patches
    >>> pos, neg = toy_patches(40, 40, seed=0)
    >>> det = train_adaboost(pos, neg, n_rounds=10, candidates=300, seed=0)
    >>> s = det.score_patches(torch.cat([pos, neg]))
    >>> bool((s[:40] > 0).float().mean() > 0.8 and (s[40:] <= 0).float().mean() > 0.8)
    True
"""

from __future__ import annotations

import math
from typing import Any

import torch
from torch import Tensor

from synthaug.detectors.base import (PatchDetector, check_image, check_patches, check_weights, register_detector,
                                     score_map_shape)
from synthaug.detectors.weak_learners import (
    DEFAULT_EPS,
    WeakLearners,
    edge_orientation_energy,
    exhaustive_candidates,
    interior_block_integrals,
    interior_orientation_maps,
)

__all__ = ["AdaBoostDetector", "train_adaboost", "best_stumps", "gradient_level"]


def gradient_level(patches: Tensor, chunk: int = 1024) -> float:
    """The median over ``patches`` of their mean gradient magnitude per pixel (the weak learners' magnitude,
    interior pixels): the gradient level of typical background, the unit of ``TrainOptions.ada_energy_floor``.

    Example:
        >>> x = torch.linspace(0, 1, 12).repeat(3, 1, 12, 1)  # a ramp of 1/11 per pixel down the rows
        >>> round(gradient_level(x), 4) == round(1 / 11, 4)
        True
    """
    patches = check_patches(patches, int(patches.shape[-1]))
    means = torch.cat([interior_orientation_maps(c.double(), 2).sum(1).mean((-2, -1)) for c in patches.split(chunk)])
    return float(means.median())


class _StumpSearch:
    """Everything about a feature matrix that does not change between boosting rounds.

    The sort order, the ±1 labels in sorted order, the threshold midpoints and
    a mask of the valid split points are computed once (features stored
    row-major, one row per feature, in chunks that stay in cache); a round is
    then one gather, one cumulative sum and two plain reductions per chunk.
    """

    def __init__(self, features: Tensor, labels: Tensor, chunk: int = 512) -> None:
        n, m = features.shape
        if labels.shape != (n,):
            raise ValueError(f"labels must be ({n},), got {tuple(labels.shape)}")
        if n < 2:
            raise ValueError(f"need at least 2 samples to place a threshold, got {n}")
        self.labels = labels.to(torch.float32)
        self.m = m
        self.chunks: list[tuple[Tensor, Tensor, Tensor, Tensor]] = []
        sign = self.labels * 2 - 1
        for c in features.T.split(chunk, dim=0):
            order = c.argsort(1)
            fs = c.gather(1, order)
            invalid = (fs[:, 1:] <= fs[:, :-1]).to(torch.float32) * 4.0  # no threshold between j and j+1
            signs = sign.index_select(0, order.reshape(-1)).view(order.shape)
            self.chunks.append((order, signs, invalid, 0.5 * (fs[:, 1:] + fs[:, :-1])))

    def _err_plus(self, w: Tensor, neg_tot: float, order: Tensor, sign: Tensor) -> Tensor:
        # p = +1 predicts 1 above the split after sorted sample j:
        # error = positives at or below j + negatives above j = Σ_{<=j} w (2y - 1) + neg_tot
        ws = w.index_select(0, order.reshape(-1)).view(order.shape)  # much faster than w[order]
        return (ws * sign).cumsum(1)[:, :-1] + neg_tot

    def _normalise(self, weights: Tensor) -> tuple[Tensor, float]:
        w = (weights / weights.sum()).to(torch.float32)
        return w, float((w * (1 - self.labels)).sum())

    def all(self, weights: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        """(error, threshold, polarity) of the best stump of every feature."""
        w, neg_tot = self._normalise(weights)
        errs, taus, pols = [], [], []
        for order, sign, invalid, mid in self.chunks:
            err_plus = self._err_plus(w, neg_tot, order, sign)
            lo = (err_plus + invalid).min(1)
            hi = (err_plus - invalid).max(1)  # p = -1 has error 1 - err_plus
            use_minus = (1.0 - hi.values) < lo.values
            err = torch.where(use_minus, 1.0 - hi.values, lo.values)
            j = torch.where(use_minus, hi.indices, lo.indices)
            errs.append(torch.where(err > 1.0, torch.full_like(err, 0.5), err))  # constant feature
            taus.append(mid.gather(1, j[:, None])[:, 0])
            pols.append(torch.where(use_minus, -1.0, 1.0))
        return torch.cat(errs), torch.cat(taus), torch.cat(pols)

    def best(self, weights: Tensor) -> tuple[int, float, float, float]:
        """(feature index, threshold, polarity, error) of the single best stump.

        Value-only reductions per chunk; the arg-reduction runs on one row only.
        """
        w, neg_tot = self._normalise(weights)
        best: tuple[float, int, int, int] = (2.0, -1, -1, 1)  # (err, chunk, row, polarity)
        for ci, (order, sign, invalid, _) in enumerate(self.chunks):
            err_plus = self._err_plus(w, neg_tot, order, sign)
            e_p = (err_plus + invalid).amin(1)
            e_m = 1.0 - (err_plus - invalid).amax(1)
            e = torch.minimum(e_p, e_m)
            r = int(e.argmin())
            if float(e[r]) < best[0]:
                best = (float(e[r]), ci, r, 1 if float(e_p[r]) <= float(e_m[r]) else -1)
        err, ci, r, pol = best
        if ci < 0 or err > 1.0:
            return 0, 0.0, 1.0, 0.5
        order, sign, invalid, mid = self.chunks[ci]
        row = self._err_plus(w, neg_tot, order[r:r + 1], sign[r:r + 1])[0]
        j = int((row + invalid[r]).argmin()) if pol == 1 else int((row - invalid[r]).argmax())
        k = sum(c[0].shape[0] for c in self.chunks[:ci]) + r
        return k, float(mid[r, j]), float(pol), err


def best_stumps(
    features: Tensor,
    labels: Tensor,
    weights: Tensor,
) -> tuple[Tensor, Tensor, Tensor]:
    """Lowest weighted error threshold and polarity of every feature column.

    A stump predicts 1 when ``p (f - τ) > 0``. Thresholds are midpoints between
    consecutive distinct sorted values; constant columns get error 0.5 (never chosen).

    Args:
        features: one column per candidate feature.
        labels: 1 for positives, 0 for negatives.
        weights: non-negative sample weights (any scale).

    Returns:
        ``(error, threshold, polarity)``, each ``(M,)``; error is normalised by
        the total weight (computed in float32).

    Shape:
        - features: (N, M)
        - labels, weights: (N,)

    Example:
        >>> f = torch.tensor([[0.1], [0.2], [0.7], [0.9]], dtype=torch.float64)
        >>> err, tau, pol = best_stumps(f, torch.tensor([0, 0, 1, 1]), torch.ones(4))
        >>> err.item(), round(tau.item(), 6), pol.item()
        (0.0, 0.45, 1.0)
    """
    if weights.shape != labels.shape:
        raise ValueError(f"weights must have the shape of labels {tuple(labels.shape)}, got {tuple(weights.shape)}")
    return _StumpSearch(features, labels).all(weights)


def train_adaboost(
    positives: Tensor,
    negatives: Tensor,
    n_rounds: int = 100,
    *,
    candidates: int | str = "exhaustive",
    n_bins: int = 4,
    step: int = 4,
    min_size: int = 4,
    eps: float = DEFAULT_EPS,
    seed: int = 0,
    stride: int = 4,
    stage_size: int = 10,
    cascade_quantile: float = 0.0,
    cascade_margin: float = 0.3,
    positive_weights: Tensor | None = None,
    energy_floor: float = 0.0,
    source_positives: int = 0,
    cascade_positives: int | None = None,
) -> "AdaBoostDetector":
    """Train discrete AdaBoost on Levi–Weiss stumps.

    Args:
        positives: object patches in [0, 1].
        negatives: background patches in [0, 1].
        n_rounds: number of boosting rounds T (stops early if no stump beats chance
            or one is perfect).
        candidates: ``"exhaustive"`` (every rectangle on a ``step`` grid × every bin)
            or an int, the size of a random subset of those (drawn with ``seed``).
        n_bins: orientation bins K.
        step: grid step of the exhaustive candidates.
        min_size: smallest rectangle side.
        eps: ε of the energy normalisation.
        seed: seed of the random candidate subset.
        stride: window step of :meth:`AdaBoostDetector.score_map`.
        stage_size: stumps per soft-cascade stage.
        cascade_quantile: rejection threshold of each stage = this quantile of
            the training positives' partial scores (0: the minimum, no training
            positive is ever rejected).
        cascade_margin: slack of the rejection thresholds, see
            :meth:`AdaBoostDetector.calibrate_cascade`.
        positive_weights: ``(P,)`` each positive's share of the positive class's starting weight (non-negative, not
            all 0): the positives start at ``0.5 · w_i / Σ w`` instead of ``0.5 / P`` (the negatives keep their half),
            so a weight of 2 boosts as the sample twice would; boosting reweights from there.
            :func:`~synthaug.detectors.video_training.share_weights` gives the real and added positives their
            shares. None: every positive the same (unchanged).
        energy_floor: the stumps' energy floor per pixel (``WeakLearners.floor``,
            :func:`~synthaug.detectors.weak_learners.edge_orientation_energy`): rectangles whose gradients are at
            the floor's level score low in every orientation. 0: the paper's energy.
        source_positives: the last this many ``positives`` come from another distribution than the images the
            detector will see (synthetic, perturbed, ...), the rest of the set (the first positives and every
            negative) from the target one. 0: plain AdaBoost. Otherwise the rounds follow Dynamic-TrAdaBoost
            (Dai et al., "Boosting for Transfer Learning", ICML 2007, with the weight correction of Al-Stouhi and
            Reddy, ECML-PKDD 2011; :func:`transfer_update`): each stump is still chosen on all weighted samples,
            but its error and α are measured on the target samples only, and a source positive the stump gets
            wrong *loses* weight (β = 1 / (1 + √(2 ln n_src / T))) instead of gaining it, so the added positives
            that look least like the target ones stop steering the later stumps. A stump whose target error is
            ≥ 1/2 is not kept and every source sample's weight is multiplied by β (the source positives steer the
            choice away from the target ones).
        cascade_positives: the soft cascade's thresholds from the first this many ``positives`` only (the real
            ones, when the rest were added), ``cascade_quantile`` and ``cascade_margin`` unchanged. None: every
            positive (a training positive is then never rejected). With the minimum (quantile 0) over every
            positive, a few added positives that score low set every stage's threshold: in the 12-seed + 20x
            synthetic drone detectors (transfer rule) the first five were 1.5-5.5x lower than after
            recalibrating on the 12 real positives, which ran those detectors 2.5x faster
            (``results/synthetic/adaboost_12/README.md``).

    Returns:
        A trained :class:`AdaBoostDetector`.

    Shape:
        - positives: (P, 1, S, S)
        - negatives: (N, 1, S, S), same S (the window)
    """
    if not isinstance(positives, Tensor) or positives.dim() != 4 or positives.shape[0] == 0:
        raise ValueError(f"positives must be a non-empty (P, 1, S, S) tensor, got {getattr(positives, 'shape', positives)}")
    window = int(positives.shape[-1])
    positives = check_patches(positives, window)
    if not isinstance(negatives, Tensor) or negatives.dim() != 4 or negatives.shape[0] == 0:
        raise ValueError(f"negatives must be a non-empty (N, 1, S, S) tensor, got {getattr(negatives, 'shape', negatives)}")
    negatives = check_patches(negatives, window)
    if not isinstance(n_rounds, int) or n_rounds < 1:
        raise ValueError(f"n_rounds must be an int >= 1, got {n_rounds}")
    if not 0.0 <= cascade_quantile < 1.0:
        raise ValueError(f"cascade_quantile must be in [0, 1), got {cascade_quantile}")
    if not (candidates == "exhaustive" or (isinstance(candidates, int) and not isinstance(candidates, bool)
                                           and candidates > 0)):
        raise ValueError(f"candidates must be 'exhaustive' or a positive int, got {candidates!r}")
    rects, orients = exhaustive_candidates(window, n_bins, step=step, min_size=min_size)
    if isinstance(candidates, int) and candidates < len(rects):
        # a random subset of the grid: keeps every rectangle on the step grid, so
        # score_map can use block-summed integral images (see AdaBoostDetector._grid)
        pick = torch.randperm(len(rects), generator=torch.Generator().manual_seed(seed))[:candidates].sort().values
        rects, orients = rects[pick], orients[pick]

    x = torch.cat([positives, negatives]).double()
    labels = torch.cat([torch.ones(len(positives)), torch.zeros(len(negatives))]).long()
    features = _features_chunked(x, rects, orients, n_bins, eps, energy_floor)  # (N, M) float64
    search = _StumpSearch(features.float(), labels)
    n_pos, n_neg = len(positives), len(negatives)
    w = torch.where(labels == 1, 0.5 / n_pos, 0.5 / n_neg).double()
    if positive_weights is not None:
        pw = check_weights(positive_weights, n_pos, flatten=True)
        w[:n_pos] = 0.5 * pw / pw.sum()
    if isinstance(source_positives, bool) or int(source_positives) != source_positives \
            or not 0 <= source_positives < n_pos:
        raise ValueError(f"source_positives must be an integer in [0, {n_pos}) (some positives must be target ones), "
                         f"got {source_positives!r}")
    if cascade_positives is not None and (isinstance(cascade_positives, bool)
                                          or int(cascade_positives) != cascade_positives
                                          or not 1 <= cascade_positives <= n_pos):
        raise ValueError(f"cascade_positives must be None or an integer in [1, {n_pos}], got {cascade_positives!r}")
    source = torch.zeros(len(labels), dtype=torch.bool)
    source[n_pos - int(source_positives): n_pos] = True
    target = ~source  # every sample in plain AdaBoost
    beta_src = 1.0 / (1.0 + math.sqrt(2.0 * math.log(source_positives) / n_rounds)) if source_positives else 1.0

    chosen: list[int] = []
    taus: list[float] = []
    pols: list[float] = []
    alphas: list[float] = []
    y_pm = labels.double() * 2 - 1
    for _ in range(n_rounds):
        k, tau_k, pol_k, _ = search.best(w)
        # the threshold is a float32 midpoint; re-measure the chosen stump's error exactly
        h = ((features[:, k] - tau_k) * pol_k > 0).double() * 2 - 1
        miss = h != y_pm
        e = float((w[target] * miss[target].double()).sum() / w[target].sum())
        if e >= 0.5 - 1e-12:
            if not source_positives:
                break
            # the stump fits the source positives but not the target samples: it is not kept, and every source
            # sample loses weight (x β), the target weights stay, so the choice is soon the target's (without this,
            # 20 synthetic positives per real one chose the same skipped stump for every remaining round)
            w = torch.where(source, w * beta_src, w)
            w = w / w.sum()
            continue
        e_c = min(max(e, 1e-10), 1 - 1e-10)
        alpha = 0.5 * math.log((1 - e_c) / e_c)
        if source_positives:
            w = transfer_update(w, miss, source, e_c, beta_src)
        else:
            w = w * torch.exp(-alpha * y_pm * h)
            w = w / w.sum()
        chosen.append(k)
        taus.append(tau_k)
        pols.append(pol_k)
        alphas.append(alpha)
        if e <= 1e-10:
            break
    if not chosen:
        raise ValueError("AdaBoost found no weak learner better than chance: are positives and negatives identical?")
    idx = torch.tensor(chosen)
    learners = WeakLearners(rects[idx], orients[idx], torch.tensor(taus), torch.tensor(pols),
                            torch.tensor(alphas), window, n_bins, eps, energy_floor)
    det = AdaBoostDetector(learners, stride=stride, stage_size=stage_size)
    calib = positives if cascade_positives is None else positives[: int(cascade_positives)]
    det.calibrate_cascade(calib, quantile=cascade_quantile, margin=cascade_margin)
    return det


def transfer_update(w: Tensor, miss: Tensor, source: Tensor, error: float, beta: float) -> Tensor:
    """One round's sample reweighting of Dynamic-TrAdaBoost (the ``source_positives`` rule of :func:`train_adaboost`).

    Target samples: a miss is multiplied by (1 - ε) / ε (AdaBoost's update, up to the normalisation). Source
    samples: a miss is multiplied by β < 1, and every source sample by the correction C = 2 (1 - ε) that keeps
    the source weights from draining only because the target misses grew (Al-Stouhi and Reddy, 2011). The
    result is normalised to sum 1.

    Args:
        w: ``(N,)`` current weights.
        miss: ``(N,)`` bool, the stump got the sample wrong.
        source: ``(N,)`` bool, the sample comes from the source (added) distribution.
        error: ε, the stump's weighted error on the target samples, in (0, 0.5).
        beta: β of the source misses, in (0, 1].

    Example:
        >>> w = transfer_update(torch.full((4,), 0.25, dtype=torch.float64), torch.tensor([True, False, True, False]),
        ...                     torch.tensor([False, False, True, True]), 0.25, 0.5)
        >>> [round(v, 4) for v in (w * 16).tolist()]  # target miss x3, target hit x1, source x1.5 x (0.5 | 1)
        [7.68, 2.56, 1.92, 3.84]
    """
    miss_d = miss.double()
    target_factor = torch.pow(torch.tensor((1.0 - error) / error, dtype=torch.float64), miss_d)
    source_factor = 2.0 * (1.0 - error) * torch.pow(torch.tensor(beta, dtype=torch.float64), miss_d)
    w = w * torch.where(source, source_factor, target_factor)
    return w / w.sum()


def _features_chunked(x: Tensor, rects: Tensor, orients: Tensor, n_bins: int, eps: float, floor: float = 0.0,
                      chunk: int = 512) -> Tensor:
    return torch.cat([edge_orientation_energy(c, rects, orients, n_bins, eps, floor) for c in x.split(chunk)])


@register_detector
class AdaBoostDetector(PatchDetector):
    """AdaBoost of Levi–Weiss stumps as a :class:`PatchDetector` (kind ``"adaboost"``).

    Args:
        learners: the selected stumps; ``learners.weights`` are the α_t.
        stride: window step of :meth:`score_map`.
        stage_size: stumps per soft-cascade stage.
        rejection: per-stage rejection thresholds on the partial score (after
            stumps ``stage_size``, ``2 stage_size``, ...); None disables the cascade.
        cascade: use the cascade in :meth:`score_map` (when ``rejection`` exists).
    """

    kind = "adaboost"

    def __init__(
        self,
        learners: WeakLearners,
        *,
        stride: int = 4,
        stage_size: int = 10,
        rejection: Tensor | None = None,
        cascade: bool = True,
    ) -> None:
        if not isinstance(learners, WeakLearners) or len(learners) == 0:
            raise ValueError(f"learners must be a non-empty WeakLearners, got {learners!r}")
        if not isinstance(stride, int) or stride < 1:
            raise ValueError(f"stride must be an int >= 1, got {stride}")
        if not isinstance(stage_size, int) or stage_size < 1:
            raise ValueError(f"stage_size must be an int >= 1, got {stage_size}")
        self.learners = learners
        self.window = int(learners.window)
        self.stride = stride
        self.stage_size = stage_size
        n_stages = math.ceil(len(learners) / stage_size)
        if rejection is not None:
            rejection = torch.as_tensor(rejection, dtype=torch.float64)
            if rejection.shape != (n_stages,):
                raise ValueError(f"rejection must have one threshold per stage ({n_stages},), got {tuple(rejection.shape)}")
        self.rejection = rejection
        self.cascade = bool(cascade)

    @property
    def alphas(self) -> Tensor:
        return self.learners.weights

    def _stage_ends(self) -> list[int]:
        t = len(self.learners)
        return [min(t, s + self.stage_size) for s in range(0, t, self.stage_size)]

    def partial_scores(self, patches: Tensor) -> Tensor:
        """Cumulative scores F_t after every stump, shape (N, T) float64."""
        patches = check_patches(patches, self.window)
        wl = self.learners
        e = edge_orientation_energy(patches.double(), wl.rects, wl.orientations, wl.n_bins, wl.eps, wl.floor)
        h = (((e - wl.thresholds.double()) * wl.polarity.double()) > 0).double()
        return ((2 * h - 1) * wl.weights.double()).cumsum(1)

    def score_patches(self, patches: Tensor) -> Tensor:
        """Exact F(X) = Σ_t α_t (2 h_t(X) - 1) (never cascaded), shape (N,) float32."""
        if patches.shape[0] == 0:
            return torch.zeros(0)
        return self.partial_scores(patches)[:, -1].float()

    def calibrate_cascade(self, positives: Tensor, quantile: float = 0.0, margin: float = 0.3) -> Tensor:
        """Set each stage's rejection threshold from the positives' partial scores.

        Stage k rejects a window whose partial score F_k is below
        ``quantile_q(F_k(positives)) - margin * A_k``, A_k = Σ α of the stumps
        so far. Training positives are fitted by boosting, so their partial
        scores are optimistic: the margin keeps unseen positives (on toy data,
        0.3 loses ~1-2 % of unseen positives that score > 0, and still drops
        ~97 % of background windows after the first stage). Calibrating on
        held-out positives with ``margin=0`` is the cleaner alternative.

        Args:
            positives: object patches (training or held-out).
            quantile: quantile of the positives' partial scores (0 = minimum).
            margin: slack in units of the accumulated α.

        Returns:
            The thresholds, shape (n_stages,); the last one is -inf.
        """
        if not 0.0 <= quantile < 1.0:
            raise ValueError(f"quantile must be in [0, 1), got {quantile}")
        if margin < 0:
            raise ValueError(f"margin must be >= 0, got {margin}")
        part = self.partial_scores(positives)
        ends = torch.tensor(self._stage_ends()) - 1
        at_ends = part[:, ends]
        rej = at_ends.min(0).values if quantile == 0 else torch.quantile(at_ends, quantile, dim=0)
        rej = rej - margin * self.alphas.double().cumsum(0)[ends] - 1e-9
        rej[-1] = -math.inf  # the last stage rejects nothing: its output is the score
        self.rejection = rej
        return rej

    def _grid(self) -> int:
        """Largest g dividing the stride and every rectangle coordinate (offset by the border ring).

        Window positions and rectangle corners then all fall on a grid of g
        pixels, so the integral images only need one value per g x g block.
        """
        r = self.learners.rects
        vals = torch.cat([r[:, 0] - 1, r[:, 1] - 1, r[:, 2], r[:, 3], torch.tensor([self.stride])])
        g = 0
        for v in vals.unique().tolist():
            g = math.gcd(g, int(v))
        return max(g, 1)

    def score_map(self, image: Tensor) -> Tensor:
        """Scores of every window on a ``stride`` grid, one stump at a time over whole maps.

        The orientation integral images are computed once for the whole image
        (float64 sums over g x g blocks when the stride and every rectangle lie
        on a grid of g pixels, see :meth:`_grid`). While most windows are alive,
        each stump is evaluated at every window at once, on its own response
        map: with P its bin's integral image and T the all-bin one,
        D = P - τ T is linear, so the stump's margin G_o - τ (G + ε) at every
        window is four shifted views of D (one row and one column difference) —
        five whole-map operations per stump, no gathers. With the cascade on,
        windows are dropped after each stage as before (see the module docstring
        for their score); once fewer than a quarter are alive, only the
        survivors' corners are gathered. Same scores as
        :meth:`_score_map_reference` (the former implementation) up to float
        rounding of the sums of α.

        Shape:
            - image: (1, 1, H, W)
            - output: ((H - window) // stride + 1, (W - window) // stride + 1)
        """
        image = check_image(image)
        h_out, w_out = score_map_shape(image.shape[-2], image.shape[-1], self.window, self.stride)
        if h_out == 0 or w_out == 0:
            return torch.zeros(max(h_out, 0), max(w_out, 0))
        wl = self.learners
        g = self._grid()
        full = interior_block_integrals(image, wl.n_bins, g)  # (K+1, h1, w1), last plane = all bins
        k, h1, w1 = full.shape[0] - 1, full.shape[1], full.shape[2]
        step = self.stride // g
        n_pos = h_out * w_out
        rh, rw = (h_out - 1) * step + 1, (w_out - 1) * step + 1  # rows/columns spanned by the window corners
        # per stump, in window blocks: top-left corner, size, plane, threshold, the margin's comparison
        y0s, x0s = ((wl.rects[:, 0] - 1) // g).tolist(), ((wl.rects[:, 1] - 1) // g).tolist()
        hs, ws = (wl.rects[:, 2] // g).tolist(), (wl.rects[:, 3] // g).tolist()
        planes, taus = wl.orientations.tolist(), wl.thresholds.double().tolist()
        offsets = wl.offsets().tolist()  # ε + floor · |R| of each stump
        positive = (wl.polarity > 0).tolist()
        alpha = wl.weights.double()
        alphas = alpha.tolist()
        remaining = alpha.flip(0).cumsum(0).flip(0)  # Σ α from stump t on
        use_cascade = self.cascade and self.rejection is not None
        total = full[k]
        d_buf = torch.empty(h1 * w1, dtype=torch.float64)
        v_buf = torch.empty(h_out * w1, dtype=torch.float64)
        margin = torch.empty(h_out, w_out, dtype=torch.float64)
        gained = torch.empty(h_out, w_out, dtype=torch.float64)
        run = torch.zeros(h_out, w_out, dtype=torch.float64)  # partial score F_t of every window
        alive: Tensor | None = None  # windows not dropped by the cascade (None: all)
        final = run  # score of the dropped windows, where alive is False
        start = 0
        stage_ends = self._stage_ends()
        for stage, end in enumerate(stage_ends):
            if alive is not None and int(alive.sum()) * 4 < n_pos:
                return self._finish_sparse(full, torch.where(alive, run, final).reshape(-1), alive.reshape(-1).nonzero()[:, 0],
                                           stage, g, h_out, w_out)
            # every window: gained = Σ_t α_t (2 h_t - 1) over the stage, one stump at a time
            gained.zero_()
            for t in range(start, end):
                y0, x0, h, w = y0s[t], x0s[t], hs[t], ws[t]
                rows, cols = slice(y0, y0 + rh + h), slice(x0, x0 + rw + w)
                d = d_buf[: (rh + h) * (rw + w)].view(rh + h, rw + w)
                torch.add(full[planes[t], rows, cols], total[rows, cols], alpha=-taus[t], out=d)
                v = v_buf[: h_out * (rw + w)].view(h_out, rw + w)
                if step == 1:
                    torch.sub(d[h:], d[:h_out], out=v)
                    torch.sub(v[:, w:], v[:, :w_out], out=margin)
                else:
                    torch.sub(d[h::step][:h_out], d[::step][:h_out], out=v)
                    torch.sub(v[:, w::step][:, :w_out], v[:, ::step][:, :w_out], out=margin)
                # margin = G_o - τ G; E > τ  <=>  G_o - τ (G + c) > 0 (c = ε + floor |R|); the in-place
                # comparison leaves 1.0 / 0.0 in margin (no bool-to-float copy)
                (margin.gt_ if positive[t] else margin.lt_)(taus[t] * offsets[t])
                gained.add_(margin, alpha=2.0 * alphas[t])
            run = run + gained.sub_(alpha[start:end].sum())
            if use_cascade and end < len(wl):
                drop = run < self.rejection[stage]
                if alive is not None:
                    drop &= alive
                if bool(drop.any()):
                    final = torch.where(drop, run - remaining[end], final)
                    alive = ~drop if alive is None else alive & ~drop
            start = end
        return (run if alive is None else torch.where(alive, run, final)).float()

    def _finish_sparse(self, full: Tensor, scores: Tensor, live: Tensor, first_stage: int, g: int, h_out: int,
                       w_out: int) -> Tensor:
        """Stages ``first_stage:`` of :meth:`score_map` at the surviving windows ``live`` only.

        ``scores`` holds the partial score of the live windows and the final one of the dropped ones.
        """
        wl = self.learners
        remaining = wl.weights.double().flip(0).cumsum(0).flip(0)
        ends = self._stage_ends()
        start = 0 if first_stage == 0 else ends[first_stage - 1]
        for stage in range(first_stage, len(ends)):
            end = ends[stage]
            part = scores[live] + self._survivor_gains(full, live, start, end, g, h_out, w_out)
            scores[live] = part
            if self.cascade and self.rejection is not None and end < len(wl):
                drop = part < self.rejection[stage]
                if bool(drop.any()):
                    scores[live[drop]] = part[drop] - remaining[end]
                    live = live[~drop]
                    if live.numel() == 0:
                        break
            start = end
        return scores.reshape(h_out, w_out).float()

    def _survivor_gains(self, full: Tensor, live: Tensor, start: int, end: int, g: int, h_out: int, w_out: int) -> Tensor:
        """Σ α_t (2 h_t - 1) of stumps ``start:end`` at the windows ``live`` only (flat gathers of their corners)."""
        wl = self.learners
        k, h1, w1 = full.shape[0] - 1, full.shape[1], full.shape[2]
        plane, step = h1 * w1, self.stride // g
        y0, x0 = (wl.rects[start:end, 0] - 1) // g, (wl.rects[start:end, 1] - 1) // g
        y1, x1 = y0 + wl.rects[start:end, 2] // g, x0 + wl.rects[start:end, 3] // g
        cy = torch.stack([y1, y0, y1, y0])  # (4, t): corners (+, -, -, +)
        cx = torch.stack([x1, x1, x0, x0])
        cc = torch.stack([wl.orientations[start:end].expand(4, -1), torch.full_like(cy, k)])  # (2, 4, t)
        base = (live // w_out) * (step * w1) + (live % w_out) * step
        vals = torch.take(full.reshape(-1), (cc * plane + cy * w1 + cx)[..., None] + base)  # (2, 4, t, P)
        sums = vals[:, 0] - vals[:, 1] - vals[:, 2] + vals[:, 3]  # bin energy, total energy
        margin = sums[0] - wl.thresholds[start:end].double()[:, None] * (sums[1] + wl.offsets()[start:end, None])
        vote = torch.where(margin * wl.polarity[start:end].double()[:, None] > 0, 1.0, -1.0).to(torch.float64)
        return wl.weights[start:end].double() @ vote

    def _score_map_reference(self, image: Tensor) -> Tensor:
        """The former :meth:`score_map` (stage-wise gathers of corner values), kept as the reference.

        Every stage copies the 8 corner values of its stumps for every live window
        out of a strided view of the integral images; :meth:`score_map` gives the
        same scores (tests compare them) several times faster.

        The orientation integral images are computed once for the whole image
        (in float64, on g x g block sums when the stride and every rectangle lie
        on a grid of g pixels, see :meth:`_grid`), and every stump is evaluated
        at all live window positions by vectorised look-ups; with the cascade
        on, positions are dropped after each stage (see the module docstring
        for their score).

        Shape:
            - image: (1, 1, H, W)
            - output: ((H - window) // stride + 1, (W - window) // stride + 1)
        """
        image = check_image(image)
        h_out, w_out = score_map_shape(image.shape[-2], image.shape[-1], self.window, self.stride)
        if h_out == 0 or w_out == 0:
            return torch.zeros(max(h_out, 0), max(w_out, 0))
        wl = self.learners
        g = self._grid()
        maps = interior_orientation_maps(image, wl.n_bins)[0]  # (K, H-2, W-2), pixel (1+i, 1+j)
        k = maps.shape[0]
        nbh, nbw = maps.shape[1] // g, maps.shape[2] // g
        maps = maps[:, : nbh * g, : nbw * g].double()
        if g > 1:
            maps = maps.reshape(k, nbh, g, nbw, g).sum((2, 4))
        ii = torch.nn.functional.pad(maps.cumsum(-1).cumsum(-2), (1, 0, 1, 0))  # (K, nbh+1, nbw+1)
        h1, w1 = ii.shape[-2:]
        full = torch.cat([ii, ii.sum(0, keepdim=True)])  # (K+1, h1, w1), last plane = all bins
        flat = full.reshape(-1)
        plane = h1 * w1
        step = self.stride // g
        n_pos = h_out * w_out
        # view (K+1, y, x, h_out, w_out): value of plane c at corner (y, x) of every window,
        # without copying; indexing it with (c, y, x) triples copies whole window grids
        grid = full.as_strided((k + 1, h1 - (h_out - 1) * step, w1 - (w_out - 1) * step, h_out, w_out),
                               (plane, w1, 1, step * w1, step))
        base = ((torch.arange(h_out) * step)[:, None] * w1 + (torch.arange(w_out) * step)[None, :]).reshape(-1)
        y0, x0 = (wl.rects[:, 0] - 1) // g, (wl.rects[:, 1] - 1) // g
        y1, x1 = y0 + wl.rects[:, 2] // g, x0 + wl.rects[:, 3] // g
        # the 4 corners (+, -, -, +) of each stump's rectangle, in its bin plane and in the total plane
        cy = torch.stack([y1, y0, y1, y0])  # (4, T)
        cx = torch.stack([x1, x1, x0, x0])
        cc = torch.stack([wl.orientations.expand(4, -1), torch.full_like(cy, k)])  # (2, 4, T)
        tau = wl.thresholds.double()
        pol = wl.polarity.double()
        alpha = wl.weights.double()
        remaining = alpha.flip(0).cumsum(0).flip(0)  # Σ α from stump t on
        use_cascade = self.cascade and self.rejection is not None
        scores = torch.zeros(n_pos, dtype=torch.float64)
        live = torch.arange(n_pos)
        start = 0
        for stage, end in enumerate(self._stage_ends()):
            t = end - start
            c_idx = cc[:, :, start:end]
            y_idx, x_idx = cy[:, start:end].expand(2, -1, -1), cx[:, start:end].expand(2, -1, -1)
            sel = None  # positions of the live windows among the evaluated ones (None: identical)
            if live.numel() == n_pos:  # every window: copy whole window grids out of the view
                vals = grid[c_idx, y_idx, x_idx].reshape(2, 4, t, n_pos)
            elif live.numel() * 16 > n_pos:  # every window of the rows that still hold a live one
                rows, row_of = torch.unique(live // w_out, return_inverse=True)
                vals = grid[c_idx[..., None], y_idx[..., None], x_idx[..., None], rows].reshape(2, 4, t, -1)
                sel = row_of * w_out + live % w_out
            else:  # a few survivors: flat gather of exactly those
                vals = torch.take(flat, (c_idx * plane + y_idx * w1 + x_idx)[..., None] + base[live])
            sums = vals[:, 0] - vals[:, 1] - vals[:, 2] + vals[:, 3]  # (2, t, P): bin energy, total energy
            # E > τ  <=>  G_o > τ (Σ_k G_k + ε): no division needed
            margin = sums[0] - tau[start:end, None] * (sums[1] + wl.offsets()[start:end, None])
            vote = torch.where(margin * pol[start:end, None] > 0, 1.0, -1.0).to(torch.float64)
            gained = alpha[start:end] @ vote
            part = scores[live] + (gained if sel is None else gained[sel])
            scores[live] = part
            if use_cascade and end < len(wl):
                drop = part < self.rejection[stage]
                if bool(drop.any()):
                    scores[live[drop]] = part[drop] - remaining[end]
                    live = live[~drop]
                    if live.numel() == 0:
                        break
            start = end
        return scores.reshape(h_out, w_out).float()

    def state_dict(self) -> dict[str, Any]:
        return {
            "learners": self.learners.state_dict(),
            "stride": int(self.stride),
            "stage_size": int(self.stage_size),
            "rejection": None if self.rejection is None else self.rejection.clone(),
            "cascade": bool(self.cascade),
        }

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> "AdaBoostDetector":
        return cls(WeakLearners.from_state_dict(state["learners"]), stride=int(state["stride"]),
                   stage_size=int(state["stage_size"]), rejection=state["rejection"],
                   cascade=bool(state["cascade"]))

    def __repr__(self) -> str:
        return (f"AdaBoostDetector(T={len(self.learners)}, window={self.window}, stride={self.stride}, "
                f"stage_size={self.stage_size}, cascade={self.cascade and self.rejection is not None})")
