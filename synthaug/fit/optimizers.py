"""Optimisers behind one interface, all minimising a batched objective over [0, 1]^D.

- ``cmaes``: CMA-ES (the ``cma`` package) with IPOP restarts; each generation
  is scored in one batched call — the fast default.
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


class Optimizer(abc.ABC):
    name: str = ""

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
    """

    name = "cmaes"

    def __init__(self, popsize: int | None = None, sigma0: float = 0.2, max_restarts: int = 3,
                 explore: float = 0.25, share_budget: bool = False, grow: float = 2.0,
                 explore_dims: tuple[int, ...] | None = None) -> None:
        if sigma0 <= 0:
            raise ValueError(f"sigma0 must be > 0, got {sigma0}")
        if not 0 <= explore < 1:
            raise ValueError(f"explore must be in [0, 1), got {explore}")
        self.popsize, self.sigma0, self.max_restarts, self.explore = popsize, sigma0, max_restarts, explore
        self.share_budget, self.grow = share_budget, grow
        self.explore_dims = explore_dims

    def minimize(self, f, dim, *, x0=None, seed=0, budget=1500, starts=None, stds=None):
        import cma

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
            # pycma draws from numpy's global generator, seeded from "seed", unless given its own "randn": its own
            # RandomState with that seed gives the same stream, and searches in other threads do not touch it
            # (the lockstep fits, synthaug.fit.lockstep)
            cma_seed = int(rng.integers(1, 2**31 - 1))
            opts = {"bounds": [0.0, 1.0], "seed": float("nan"), "randn": np.random.RandomState(cma_seed).randn,
                    "popsize": pop, "verbose": -9, "maxfevals": share, "tolfun": 1e-9, "tolx": 1e-7}
            if cma_stds is not None:
                opts["CMA_stds"] = list(cma_stds)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                es = cma.CMAEvolutionStrategy(start, sigma0, opts)
                while not es.stop() and track.n < budget:
                    xs = es.ask()
                    if track.n + len(xs) > budget:
                        break
                    es.tell(xs, list(track(np.asarray(xs))))
            restarts += 1
            pop = int(pop * self.grow)
            start = starts.pop(0) if starts else rng.random(dim)
            if track.n + pop > budget:
                break
        return OptimResult(track.best_x, track.best, track.n, time.perf_counter() - t0, restarts - 1, track.trace)


class SimulatedAnnealing(Optimizer):
    """The paper's simulated annealing: ``scipy.optimize.dual_annealing`` (no local search)."""

    name = "anneal"

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


_OPTIMIZERS = {"cmaes": CMAES, "anneal": SimulatedAnnealing, "random": RandomSearch}


def get_optimizer(name: str, **kwargs) -> Optimizer:
    try:
        return _OPTIMIZERS[name](**kwargs)
    except KeyError:
        raise ValueError(f"unknown optimizer {name!r}; choose from {sorted(_OPTIMIZERS)}") from None


def list_optimizers() -> list[str]:
    return sorted(_OPTIMIZERS)
