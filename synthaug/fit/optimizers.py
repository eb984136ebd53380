"""Optimisers behind one interface, all minimising a batched objective over [0, 1]^D.

- ``cmaes``: CMA-ES with IPOP restarts, each generation scored in one batched call — the default; its runs are
  :class:`CMAState`'s (pycma's default strategy in numpy, its bound transform vectorised, its normal stream:
  pycma's runs up to rounding at ~6x less optimiser time). ``cmaes_numpy`` is its former name (one release).
- ``cmaes_pycma``: the same restarts on the ``cma`` package itself (the reference; the default until stop 27).
- ``anneal``: simulated annealing as in the paper, via
  ``scipy.optimize.dual_annealing`` without local search (one candidate per
  call): the reference.
- ``random``: uniform random search in batches (a sanity baseline).

All take an explicit ``seed`` and an evaluation ``budget`` and return an
:class:`OptimResult` with the best point, its value and a trace of
(evaluations, best value so far).

Example:
    >>> import numpy as np
    >>> f = lambda u: ((np.atleast_2d(u) - 0.3) ** 2).sum(1)
    >>> r = get_optimizer("cmaes").minimize(f, 3, seed=0, budget=800)
    >>> bool(r.fun < 1e-6), r.n_evals <= 800
    (True, True)
"""

from __future__ import annotations

import abc
import math
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

Objective = Callable[[np.ndarray], np.ndarray]

# raised whenever a change to an optimiser here changes the points it visits (a fit's fingerprint records it)
IMPLEMENTATION_VERSION = 2
# the numpy engine's own version (CMAState, and the fit's grid refinement run on it): 3 = pycma's default strategy
# step for step; 4 = the pose-grid start's short refinements on the numpy engine too (synthaug.fit.starts)
CMASTATE_VERSION = 4


@dataclass
class OptimResult:
    x: np.ndarray
    fun: float
    n_evals: int
    wall_s: float
    restarts: int = 0
    trace: list[tuple[int, float]] = field(default_factory=list)

    def stats(self) -> dict:
        return {"n_evals": int(self.n_evals), "wall_s": round(float(self.wall_s), 4), "restarts": int(self.restarts),
                "trace": [[int(n), float(v)] for n, v in self.trace]}


class _Tracker:
    def __init__(self, f: Objective, budget: int) -> None:
        self.f, self.budget = f, budget
        self.n, self.best, self.best_x = 0, math.inf, None
        self.trace: list[tuple[int, float]] = []

    def __call__(self, u: np.ndarray) -> np.ndarray:
        u = np.atleast_2d(u)
        vals = np.asarray(self.f(u), dtype=float)
        self.n += len(u)
        k = int(np.argmin(vals))
        if vals[k] < self.best:
            self.best, self.best_x = float(vals[k]), np.array(u[k], dtype=float)
            self.trace.append((self.n, self.best))
        return vals


def to_unit_box(x: np.ndarray, margin: float = 0.05) -> np.ndarray:
    """Map unbounded points into [0, 1] element-wise: linear inside, quadratic within ``margin`` of a bound,
    mirrored and periodic outside — the ``cma`` package's ``BoxConstraintsLinQuadTransformation`` for the
    bounds [0, 1] (its margin 0.05), vectorised. Smooth everywhere, so a bound is reached with a vanishing step.

    Example:
        >>> to_unit_box(np.array([-0.05, 0.0, 0.5, 1.05, 1.3, -0.3])).round(4).tolist()
        [0.0, 0.0125, 0.5, 1.0, 0.8, 0.2]
    """
    a = margin
    x = np.asarray(x, float)
    period, start = 2 * (1 + 2 * a), -2 * a - 0.5
    x = np.where((x < start) | (x > 1 + 2 * a + 0.5), x - period * np.floor((x - start) / period), x)
    x = np.where(x > 1 + a, 2 * (1 + a) - x, x)
    x = np.where(x < -a, -2 * a - x, x)
    return np.where(x < a, (x + a) ** 2 / (4 * a), np.where(x < 1 - a, x, 1 - (x - (1 + a)) ** 2 / (4 * a)))


def from_unit_box(y: np.ndarray, margin: float = 0.05) -> np.ndarray:
    """The genotype in [-margin, 1 + margin] that :func:`to_unit_box` maps to ``y`` in [0, 1] (where a run starts).

    Example:
        >>> from_unit_box(np.array([0.0, 0.0125, 0.5, 1.0])).round(4).tolist()
        [-0.05, 0.0, 0.5, 1.05]
    """
    a = margin
    y = np.clip(np.asarray(y, float), 0.0, 1.0)
    return np.where(y < a, -a + 2 * np.sqrt(a * y), np.where(y < 1 - a, y, 1 + a - 2 * np.sqrt(a * (1 - y))))


class CMAState:
    """One CMA-ES run in numpy, ask/tell, on the box [0, 1]^D: the ``cma`` package's (pycma 4.x) default strategy
    step for step, vectorised — active CMA with its recombination weights and learning rates, its cumulative
    step-size adaptation (c_sigma, d_sigma, the change clipped to a factor e), its h_sigma test, its lazy
    eigendecomposition, its start covariance, its cap of every coordinate's standard deviation at a third of the
    box (``maxstd_boundrange``, taken out of the coordinate's scale) and its stopping rules for the options we use.
    Given pycma's normal stream (``rng`` a ``np.random.RandomState`` seeded as pycma's ``randn``), the points it
    asks are pycma's up to rounding (tests/test_cmaes.py follows both runs generation by generation).

    Candidates are drawn in an unbounded genotype space and evaluated at their image in [0, 1]
    (:func:`to_unit_box`, pycma's bound transform vectorised: pycma loops over the candidates in Python, 40 %
    of its 1.3 ms per 12-D generation). ``stds`` scales the coordinates (pycma's ``CMA_stds``). Stopping rules as
    pycma's: ``maxfevals``, ``tolfacupx``, ``tolx``, ``tolfun`` (the current values and the best of the last
    10 + 30 D / lambda generations span less), ``tolfunhist``, ``tolxstagnation``, ``tolupsigma``,
    ``noeffectcoord``, ``noeffectaxis``, ``tolconditioncov`` and ``tolflatfitness`` (the best value equals the
    75th percentile two generations running); not ``tolstagnation``, which needs 500+ generations.

    ``mean`` is the start in [0, 1]^D; the attribute ``mean`` is the genotype (its image: ``to_unit_box(mean)``).

    Example:
        >>> es = CMAState(np.full(2, 0.5), 0.2, popsize=8, rng=np.random.default_rng(0))
        >>> for _ in range(60):
        ...     x = es.ask()
        ...     es.tell(((x - 0.3) ** 2).sum(1))
        >>> bool(np.allclose(to_unit_box(es.mean), 0.3, atol=1e-3))
        True
    """

    # pycma's defaults for the rules it applies on its own (options we do not set)
    TOLFUNHIST, TOLFACUPX, TOLUPSIGMA, TOLCONDITIONCOV, TOLFLATFITNESS = 1e-12, 1e3, 1e20, 1e14, 1
    TOLXSTAGNATION = (1e-9, 20, 0.1)
    MAXSTD = 1 / 3  # pycma's maxstd_boundrange times the box's width

    def __init__(self, mean: np.ndarray, sigma: float, *, popsize: int,
                 rng: np.random.Generator | np.random.RandomState, stds: np.ndarray | None = None,
                 tolfun: float = 1e-9, tolx: float = 1e-7, maxfevals: int | None = None) -> None:
        n = int(np.asarray(mean).size)
        self.maxfevals = maxfevals
        self.n, self.lam, self.rng = n, int(popsize), rng
        if isinstance(rng, np.random.RandomState):  # pycma's stream: randn(lambda, n) per generation
            self._randn = lambda k: rng.randn(k, n)
        else:
            self._randn = lambda k: rng.standard_normal((k, n))
        self.scale = np.ones(n) if stds is None else np.array(stds, float) * np.ones(n)   # pycma's sigma_vec
        self.scale0 = self.scale.copy()
        self.mean = from_unit_box(mean)   # the genotype
        self.sigma0 = self.sigma = float(sigma)
        self.tolfun, self.tolx = tolfun, tolx
        lam = self.lam
        wp = math.log((lam + 1) / 2) - np.log(np.arange(1, lam + 1))  # all lambda weights, the worst negative
        mu = int((wp > 0).sum())
        pos, neg = wp[:mu], wp[mu:]
        me = float(pos.sum() ** 2 / (pos ** 2).sum())
        me_neg = float(neg.sum() ** 2 / (neg ** 2).sum()) if neg.size else 0.0
        self.mueff = me
        self.cc = (4 + me / n) / (n + 4 + 2 * me / n)
        self.c1 = 2 / ((n + 1.3) ** 2 + me)
        self.cmu = min(1 - self.c1, 2 * (0.25 + me + 1 / me - 2) / ((n + 2) ** 2 + me))
        a_neg = min(1 + self.c1 / self.cmu, 1 + 2 * me_neg / (me + 2), (1 - self.c1 - self.cmu) / (n * self.cmu))
        self.weights = np.concatenate([pos / pos.sum(), a_neg * neg / np.abs(neg).sum() if neg.size else neg])
        self.mu = mu
        # pycma's CSA (cma/sigma_adaptation.py: compute_cs, compute_damps with its module defaults)
        self.cs = min(0.5, (me + 2) / (n + me + 3))
        damp_in = max(1.0, 3 * (1 - 0.5 ** (n / 9)))
        self.damps = 1 + 2 * max(0.0, damp_in * math.sqrt((me - 1) / (n + 1)) - 1) + self.cs
        # E||N(0, I)||: exact up to 100 dimensions (pycma tabulates it), pycma's approximation above
        self.chin = math.sqrt(2) * math.exp(math.lgamma((n + 1) / 2) - math.lgamma(n / 2)) if n <= 100 else \
            math.sqrt(n) * (1 - 1 / (4 * n) + 1 / (32 * n * n))
        self.pc, self.ps = np.zeros(n), np.zeros(n)
        # pycma's start covariance: the identity with a tiny spread that keeps its eigenvalues distinct
        self.C = np.diag(np.exp((1e-4 / n) * np.arange(n)))
        self.B, self.D = np.eye(n), np.sqrt(np.diag(self.C))
        self.lazy_gap = 1 / (self.c1 + self.cmu + 1e-23) / n / 10
        self.count_tell = self.last_update = 0
        self.gen = 0
        self.best_history: list[float] = []     # the best value per generation (all of them)
        self._hist: list[float] = []            # pycma's fit.hist: the last 10 + 30 n / lambda bests, newest first
        self._flat = 0
        self._xstag = [self.mean, 0, 0]         # tolxstagnation: (x, count, count_x)
        self.stop_reason: str | None = None
        self._x: np.ndarray | None = None
        self._stds_into_limits()

    def _decompose(self) -> None:
        """pycma's lazy update (GaussFullSampler.update_now): C's eigensystem once ``lazy_gap`` tells have passed."""
        if self.count_tell < self.last_update + self.lazy_gap or \
                self.lazy_gap == self.count_tell - self.last_update == 0:
            return
        self.C = (self.C + self.C.T) / 2
        d2, B = np.linalg.eigh(self.C)
        if np.any(d2 <= 0):
            raise FloatingPointError(f"covariance matrix not positive definite (min eigenvalue {d2.min():g})")
        idx = np.argsort(d2)
        self.D, self.B = np.sqrt(d2[idx]), B[:, idx]
        self.last_update = self.count_tell

    def ask(self) -> np.ndarray:
        """``popsize`` candidates (lambda, D) in [0, 1]."""
        self._decompose()
        z = self._randn(self.lam)
        self._x = self.mean + self.sigma * (self.scale * ((z * self.D) @ self.B.T))   # genotypes
        return to_unit_box(self._x)

    def tell(self, values: np.ndarray) -> None:
        """The values of the last :meth:`ask`'s candidates, in its order."""
        if self._x is None:
            raise RuntimeError("tell() before ask()")
        values = np.asarray(values, float)
        n, w, lam = self.n, self.weights, len(values)
        self.gen += 1
        order = np.argsort(values)                    # as pycma (not a stable sort)
        fit = values[order]
        self._hist.insert(0, float(fit[0]))
        if len(self._hist) > 10 + 30 * n / self.lam:
            self._hist.pop()
        pop = self._x[order]                          # genotypes, best first
        mold = self.mean
        self.mean = w[: self.mu] @ pop[: self.mu]
        dm = (self.mean - mold) / self.scale
        ims = self.B @ ((self.B.T @ dm) / self.D) * (math.sqrt(self.mueff) / self.sigma)
        self.ps = (1 - self.cs) * self.ps + math.sqrt(self.cs * (2 - self.cs)) * ims
        hsig = float(np.sum(self.ps ** 2) / (1 - (1 - self.cs) ** (2 * self.gen)) / n - 1 < 1 + 4 / (n + 1))
        cc = self.cc
        c1a = self.c1 * (1 - (1 - hsig ** 2) * cc * (2 - cc))
        self.pc = (1 - cc) * self.pc + hsig * (math.sqrt(cc * (2 - cc) * self.mueff) / self.sigma) * dm
        ys = (pop - mold) / (self.sigma * self.scale)
        # the sampler's update (cma.sampler.GaussFullSampler.update): the negative weights rescaled by the
        # Mahalanobis length under the current eigensystem
        wc = self.cmu * w[:lam]
        self.C *= 1 - (c1a + wc.sum())
        neg = wc < 0
        if neg.any():
            norm = np.sqrt((((ys[neg] @ self.B) / self.D) ** 2).sum(1))
            wc[neg] *= n / (norm + 1e-9) ** 2
        pc = math.sqrt(self.c1 / (c1a + 1e-23)) * self.pc
        self.C += c1a * np.outer(pc, pc) + (ys.T * wc) @ ys
        self.count_tell += 1
        s = (self.cs / self.damps) * (float(np.linalg.norm(self.ps)) / self.chin - 1)
        self.sigma *= math.exp(min(1.0, max(-1.0, s)))
        self._stds_into_limits()
        self._x = None
        self._check_stop(fit)

    def _stds_into_limits(self) -> None:
        """pycma's ``maxstd``: a coordinate whose standard deviation exceeds a third of the box gets a smaller scale."""
        stds = self.sigma * self.scale * np.sqrt(np.diag(self.C))
        fix = math.exp(1e-4) if self.gen <= 2 else 1.0
        big = stds > self.MAXSTD * fix
        if big.any():
            self.scale[big] *= self.MAXSTD / stds[big]

    def _check_stop(self, fit: np.ndarray) -> None:
        self.best_history.append(float(fit[0]))
        n, lam = self.n, len(fit)
        # tolxstagnation's bookkeeping (cma.evolution_strategy._StopTolXStagnation.update)
        x, count, count_x = self._xstag
        count += 1
        d0, t0, t1 = self.TOLXSTAGNATION
        delta = d0 * max(1.0, (count - count_x) / (t0 + t1 * count)) ** 0.5
        if float(np.sqrt(np.sum((x - self.mean) ** 2))) > delta:
            x, count_x = self.mean, count
        self._xstag = [x, count, count_x]
        # the flat-fitness counter runs every generation, as in pycma
        if fit[0] < fit[int(0.75 * lam)]:
            self._flat = 0
        else:
            self._flat += 1
        sd = self.sigma * self.scale * np.sqrt(np.diag(self.C))
        frange, hrange = float(fit[-1] - fit[0]), max(self._hist) - min(self._hist)
        i = self.gen % n
        if self.maxfevals is not None and self.gen * self.lam - 1 >= self.maxfevals:
            self.stop_reason = "maxfevals"
        elif np.any(sd > self.sigma0 * self.scale0 * self.TOLFACUPX):
            self.stop_reason = "tolfacupx"
        elif np.all(sd < self.tolx) and np.all(self.sigma * self.scale * np.abs(self.pc) < self.tolx):
            self.stop_reason = "tolx"
        elif frange < self.tolfun and hrange < self.tolfun:
            self.stop_reason = "tolfun"
        elif len(self._hist) > 9 and hrange < self.TOLFUNHIST:
            self.stop_reason = "tolfunhist"
        elif count - count_x > t0 + t1 * count:
            self.stop_reason = "tolxstagnation"
        elif self.sigma / self.D.max() > self.sigma0 * self.TOLUPSIGMA:
            self.stop_reason = "tolupsigma"
        elif np.any(self.mean == self.mean + 0.2 * sd):
            self.stop_reason = "noeffectcoord"
        elif np.all(self.mean == self.mean + 0.1 * self.sigma * self.D[i] * self.scale * self.B[:, i]):
            self.stop_reason = "noeffectaxis"
        elif self.D[-1] > self.TOLCONDITIONCOV ** 0.5 * self.D[0]:
            self.stop_reason = "tolconditioncov"
        elif self._flat > self.TOLFLATFITNESS:
            self.stop_reason = "tolflatfitness"

    def stop(self) -> bool:
        return self.stop_reason is not None


class Optimizer(abc.ABC):
    name: str = ""

    def implementation(self) -> str:
        """What computes this optimiser's steps, with its version: a fit records it, and a fit made by another
        implementation is not reused (:func:`synthaug.fit.fingerprint.fit_inputs`)."""
        return f"synthaug {self.name} {IMPLEMENTATION_VERSION}"

    @abc.abstractmethod
    def minimize(self, f: Objective, dim: int, *, x0: np.ndarray | None = None, seed: int = 0,
                 budget: int = 1500, starts: np.ndarray | None = None,
                 stds: np.ndarray | None = None) -> OptimResult:
        """Minimise ``f`` over [0, 1]^D within ``budget`` evaluations.

        ``starts`` (K, D), best first, are start points chosen by the caller (a
        structured initialisation, e.g. a pose grid): CMA-ES takes them as the
        means of its first run and restarts instead of its uniform look, with
        per-coordinate step sizes ``stds`` (D,) in [0, 1]-units; the other
        optimisers start from ``starts[0]``.
        """


class CMAES(Optimizer):
    """CMA-ES after a batched uniform exploration, with IPOP restarts.

    A fraction ``explore`` of the budget is spent on uniform samples (one
    batched call); CMA-ES then starts from the best of them, and restarts (with
    a population ``grow`` times larger, IPOP) from the next best distinct ones.

    Args:
        popsize: first population size (default 4 + 3 ln D, at least 12).
        sigma0: initial step size in [0, 1]-units.
        max_restarts: restarts while budget remains.
        explore: fraction of the budget spent on the uniform look.
        share_budget: split the remaining budget evenly between runs (else a run
            goes on until CMA-ES's own stopping rules).
        grow: population factor per restart.
        engine: ``"numpy"`` (the default: :class:`CMAState`, pycma's default strategy step for step with the same
            seeded normal stream, so pycma's runs up to rounding at a fraction of its per-generation cost) or
            ``"pycma"`` (the ``cma`` package itself: ``cmaes_pycma``; the two side by side:
            ``benchmarks/bench_fit.py --optimizers cmaes_pycma cmaes``).
    """

    name = "cmaes"

    def __init__(self, popsize: int | None = None, sigma0: float = 0.2, max_restarts: int = 3,
                 explore: float = 0.25, share_budget: bool = False, grow: float = 2.0,
                 explore_dims: tuple[int, ...] | None = None, engine: str = "numpy") -> None:
        if sigma0 <= 0:
            raise ValueError(f"sigma0 must be > 0, got {sigma0}")
        if not 0 <= explore < 1:
            raise ValueError(f"explore must be in [0, 1), got {explore}")
        self.popsize, self.sigma0, self.max_restarts, self.explore = popsize, sigma0, max_restarts, explore
        self.share_budget, self.grow = share_budget, grow
        self.explore_dims = explore_dims
        if engine not in ("numpy", "pycma"):
            raise ValueError(f"engine must be 'numpy' or 'pycma', got {engine!r}")
        self.engine = engine

    def implementation(self) -> str:
        if self.engine == "numpy":
            return super().implementation() + f" (numpy CMAState {CMASTATE_VERSION})"
        import cma

        return super().implementation() + f" (pycma {cma.__version__})"

    def _engine_run(self, start: np.ndarray, sigma0: float, stds: np.ndarray | None, *, pop: int, maxfevals: int,
                    seed: int) -> "CMAState | _PyCMARun":
        """One CMA-ES run (ask / tell / stop) from ``start`` with its own generator seeded by ``seed``."""
        if self.engine == "numpy":
            # pycma's normal stream for the same seed (_PyCMARun): the two engines' runs coincide up to rounding
            return CMAState(start, sigma0, popsize=pop, rng=np.random.RandomState(seed), stds=stds, maxfevals=maxfevals)
        return _PyCMARun(start, sigma0, stds, pop=pop, maxfevals=maxfevals, seed=seed)

    def minimize(self, f, dim, *, x0=None, seed=0, budget=1500, starts=None, stds=None):
        t0 = time.perf_counter()
        track = _Tracker(f, budget)
        rng = np.random.default_rng(seed)
        pop = self.popsize or max(12, 4 + int(3 * math.log(dim)))
        restarts = 0
        given = starts is not None
        sigma0, cma_stds = self.sigma0, None
        if given:
            starts = [np.asarray(s, float) for s in np.atleast_2d(np.asarray(starts, float))]
            if not starts or any(s.shape != (dim,) for s in starts):
                raise ValueError(f"starts must be a non-empty (K, {dim}) array")
            if stds is not None:
                cma_stds = np.asarray(stds, float)
                if cma_stds.shape != (dim,) or not np.all(cma_stds > 0):
                    raise ValueError(f"stds must be ({dim},) positive step sizes")
                sigma0 = 1.0
        else:
            starts = []
        n_explore = 0 if given else int(self.explore * budget)
        if n_explore > 0:
            # a batched uniform look over the whole box first: the pose part of the
            # landscape is multimodal, and CMA-ES restarts from the best distinct points
            if self.explore_dims is None:
                xs = rng.random((n_explore, dim))
            else:  # explore only these coordinates (e.g. the pose), the others stay at x0
                base = np.full(dim, 0.5) if x0 is None else np.clip(np.asarray(x0, float), 0, 1)
                xs = np.repeat(base[None], n_explore, axis=0)
                dims = list(self.explore_dims)
                xs[:, dims] = rng.random((n_explore, len(dims)))
            if x0 is not None:
                xs[0] = np.clip(np.asarray(x0, float), 0, 1)
            vals = track(xs)
            starts = [xs[i] for i in np.argsort(vals)[: self.max_restarts + 1]]
        start = starts.pop(0) if starts else (np.full(dim, 0.5) if x0 is None else np.clip(np.asarray(x0, float), 0, 1))
        max_restarts = max(self.max_restarts, len(starts) - 1) if given else self.max_restarts
        while track.n < budget and restarts <= max_restarts:
            # share what is left between this run and the restarts still to come
            runs_left = max_restarts + 1 - restarts
            share = budget - track.n if (runs_left <= 1 or not self.share_budget) else max((budget - track.n) // runs_left, 4 * pop)
            cma_seed = int(rng.integers(1, 2**31 - 1))  # the run's own generator (_engine_run)
            es = self._engine_run(start, sigma0, cma_stds, pop=pop, maxfevals=share, seed=cma_seed)
            while not es.stop() and track.n < budget:
                xs = np.asarray(es.ask())
                if track.n + len(xs) > budget:
                    break
                es.tell(track(xs))
            restarts += 1
            pop = int(pop * self.grow)
            start = starts.pop(0) if starts else rng.random(dim)
            if track.n + pop > budget:
                break
        return OptimResult(track.best_x, track.best, track.n, time.perf_counter() - t0, restarts - 1, track.trace)


class _PyCMARun:
    """One pycma run with :class:`CMAState`'s ask / tell / stop (the ``"pycma"`` engine of :class:`CMAES`)."""

    def __init__(self, start: np.ndarray, sigma0: float, stds: np.ndarray | None, *, pop: int, maxfevals: int,
                 seed: int) -> None:
        import cma

        # pycma draws from numpy's global generator unless given its own "randn": its own RandomState keeps
        # searches in other threads (the lockstep fits, synthaug.fit.lockstep) off each other's stream
        opts = {"bounds": [0.0, 1.0], "seed": float("nan"), "randn": np.random.RandomState(seed).randn,
                "popsize": pop, "verbose": -9, "maxfevals": maxfevals, "tolfun": 1e-9, "tolx": 1e-7}
        if stds is not None:
            opts["CMA_stds"] = list(stds)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.es = cma.CMAEvolutionStrategy(start, sigma0, opts)

    def ask(self) -> np.ndarray:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self._xs = self.es.ask()
        return np.asarray(self._xs)

    def tell(self, values: np.ndarray) -> None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.es.tell(self._xs, list(np.asarray(values, float)))

    def stop(self) -> bool:
        return bool(self.es.stop())


class SimulatedAnnealing(Optimizer):
    """The paper's simulated annealing: ``scipy.optimize.dual_annealing`` (no local search)."""

    name = "anneal"

    def implementation(self) -> str:
        import scipy

        return super().implementation() + f" (scipy {scipy.__version__} dual_annealing)"

    def minimize(self, f, dim, *, x0=None, seed=0, budget=1500, starts=None, stds=None):
        from scipy.optimize import dual_annealing

        if starts is not None:
            x0 = np.atleast_2d(np.asarray(starts, float))[0]
        t0 = time.perf_counter()
        track = _Tracker(f, budget)

        def scalar(u: np.ndarray) -> float:
            return float(track(u[None])[0])

        dual_annealing(scalar, bounds=[(0.0, 1.0)] * dim, maxfun=budget, seed=seed, no_local_search=True,
                       x0=None if x0 is None else np.clip(np.asarray(x0, float), 0, 1))
        return OptimResult(track.best_x, track.best, track.n, time.perf_counter() - t0, 0, track.trace)


class RandomSearch(Optimizer):
    name = "random"

    def __init__(self, batch: int = 256) -> None:
        self.batch = batch

    def minimize(self, f, dim, *, x0=None, seed=0, budget=1500, starts=None, stds=None):
        t0 = time.perf_counter()
        track = _Tracker(f, budget)
        rng = np.random.default_rng(seed)
        if starts is not None:
            x0 = np.atleast_2d(np.asarray(starts, float))[0]
        if x0 is not None:
            track(np.asarray(x0, float)[None])
        while track.n < budget:
            track(rng.random((min(self.batch, budget - track.n), dim)))
        return OptimResult(track.best_x, track.best, track.n, time.perf_counter() - t0, 0, track.trace)


class PyCMAES(CMAES):
    """:class:`CMAES` on the ``cma`` package (``engine="pycma"``), the reference the numpy engine follows.

    The default engine changed to numpy in stop 27: quiet box, ``benchmarks/bench_fit.py --n 8 --budget 3500
    --reference-budget 15000 --fit-path --lockstep 8 --repeats 3 --workers 2 --fit-seeds 32 --optimizers cmaes_pycma
    cmaes`` (``results/bench/fit_quiet_stop27.json``): the same 7 of 8 seeds within 5 % of the reference annealing and
    the same median distance, ``synthaug fit --workers 2`` 0.419 s per seed against pycma's 0.525 (lockstep, one
    core: 0.609 vs 0.810); over 3 optimiser seeds 20 of 24 fits within 5 % for both (the same fits to 3 digits on 22).
    """

    name = "cmaes_pycma"

    def __init__(self, **kwargs) -> None:
        kwargs.setdefault("engine", "pycma")
        super().__init__(**kwargs)


class NumpyCMAES(CMAES):
    """The former name of the default :class:`CMAES` (numpy engine), kept for one release: ``cmaes_numpy``."""

    name = "cmaes_numpy"

    def __init__(self, **kwargs) -> None:
        kwargs.setdefault("engine", "numpy")
        super().__init__(**kwargs)


_OPTIMIZERS = {"cmaes": CMAES, "cmaes_pycma": PyCMAES, "cmaes_numpy": NumpyCMAES, "anneal": SimulatedAnnealing,
               "random": RandomSearch}


def get_optimizer(name: str, **kwargs) -> Optimizer:
    try:
        return _OPTIMIZERS[name](**kwargs)
    except KeyError:
        raise ValueError(f"unknown optimizer {name!r}; choose from {sorted(_OPTIMIZERS)}") from None


def list_optimizers() -> list[str]:
    return sorted(_OPTIMIZERS)
