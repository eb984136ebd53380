"""The numpy CMA-ES (synthaug.fit.optimizers.CMAState) against independent references: the ``cma`` package's
strategy constants, Hansen's tutorial formulas (arXiv:1604.00772, table 1) computed by hand, and the ``cma``
package's search on the same budgets (``CMAES(engine="pycma")``, the default ``cmaes``)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from synthaug.fit.optimizers import CMAES, CMAState, from_unit_box, get_optimizer, to_unit_box

cma = pytest.importorskip("cma")


@pytest.mark.parametrize("n, lam", [(12, 12), (12, 24), (5, 9), (3, 48)])
def test_strategy_constants_equal_pycma_and_the_tutorial(n, lam):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = cma.CMAEvolutionStrategy(np.full(n, 0.5), 0.2, {"popsize": lam, "verbose": -9}).sp
    es = CMAState(np.full(n, 0.5), 0.2, popsize=lam, rng=np.random.default_rng(0))
    # recombination weights incl. the active (negative) ones, mu_eff and the learning rates: as pycma's
    np.testing.assert_allclose(es.weights, np.asarray(ref.weights), rtol=1e-12, atol=1e-15)
    for ours, theirs in ((es.mueff, ref.weights.mueff), (es.cc, ref.cc), (es.c1, ref.c1), (es.cmu, ref.cmu)):
        assert ours == pytest.approx(theirs, rel=1e-12)
    # step-size constants: the tutorial's (pycma uses an older c_sigma), by hand
    me = es.mueff
    assert es.cs == pytest.approx((me + 2) / (n + me + 5))
    assert es.damps == pytest.approx(1 + 2 * max(0, math.sqrt((me - 1) / (n + 1)) - 1) + es.cs)
    assert es.weights[: lam // 2].sum() == pytest.approx(1.0)
    assert (es.weights[: es.mu] > 0).all() and (es.weights[es.mu:] <= 0).all()


def test_the_box_transform_equals_pycmas_and_inverts():
    from cma.transformations import BoxConstraintsLinQuadTransformation

    ref = BoxConstraintsLinQuadTransformation([[0.0, 1.0]] * 1000)
    ref.initialize(1000)
    x = np.random.default_rng(0).normal(0.5, 2.0, 1000)
    x[:6] = [-0.05, 0.05, 0.95, 1.05, -10.0, 13.7]
    y = to_unit_box(x)
    np.testing.assert_allclose(y, np.asarray(ref(x.copy())), rtol=0, atol=1e-12)
    assert ((0 <= y) & (y <= 1)).all()
    u = np.random.default_rng(1).random(1000)
    u[:3] = [0.0, 1.0, 0.5]
    g = from_unit_box(u)
    np.testing.assert_allclose(to_unit_box(g), u, atol=1e-12)
    np.testing.assert_allclose(g, [ref.inverse(np.array([v]))[0] for v in u], atol=1e-12)


def test_covariance_stays_symmetric_positive_definite_and_learns_the_scaling():
    """On an ellipsoid with axis ratio 100 the covariance learns the inverse Hessian's shape: condition ~1e4 and the
    long axis along the flat coordinate (checked before the run nears machine precision)."""
    scales = np.array([1.0, 100.0])
    es = CMAState(np.array([0.8, 0.8]), 0.1, popsize=8, rng=np.random.default_rng(3))
    for _ in range(60):
        x = es.ask()
        es.tell((((x - 0.5) * scales) ** 2).sum(1))
        assert np.allclose(es.C, es.C.T) and np.linalg.eigvalsh(es.C).min() > 0
    w, v = np.linalg.eigh(es.C)
    assert 3e3 < w[-1] / w[0] < 3e4
    assert abs(v[0, -1]) > 0.99  # the widest axis is the first (flat) coordinate
    assert np.allclose(to_unit_box(es.mean * es.scale), 0.5, atol=1e-5)


def _functions():
    def sphere(u):
        return ((u - 0.3) ** 2).sum(1)

    def ellipsoid(u):
        d = u.shape[1]
        return (10 ** (6 * np.arange(d) / (d - 1)) * (u - 0.6) ** 2).sum(1)

    def rosenbrock(u):
        x = 4 * u - 2
        return (100 * (x[:, 1:] - x[:, :-1] ** 2) ** 2 + (1 - x[:, :-1]) ** 2).sum(1)

    def on_bound(u):  # the optimum on the box's corner, as a fitted parameter at its bound
        return (u ** 2).sum(1) + 0.1 * u[:, 0]

    return {"sphere": sphere, "ellipsoid": ellipsoid, "rosenbrock": rosenbrock, "on_bound": on_bound}


@pytest.mark.parametrize("name", list(_functions()))
def test_numpy_engine_searches_as_well_as_pycma(name):
    """The same restarts, starts and budgets (the fit's path: given starts and per-coordinate steps), 6 seeds:
    the numpy engine's median best value is no worse than 1.5x the cma package's (or both are at the optimum)."""
    f = _functions()[name]
    d, budget = 8, 1500
    ours, theirs = [], []
    for seed in range(6):
        starts = np.random.default_rng(100 + seed).random((3, d))
        kw = dict(seed=seed, budget=budget, starts=starts, stds=np.full(d, 0.15))
        a = CMAES(engine="numpy").minimize(f, d, **kw)
        b = CMAES(engine="pycma").minimize(f, d, **kw)
        assert a.n_evals <= budget and b.n_evals <= budget
        np.testing.assert_allclose(f(a.x[None])[0], a.fun)
        assert ((0 <= a.x) & (a.x <= 1)).all()
        ours.append(a.fun)
        theirs.append(b.fun)
    assert np.median(ours) <= 1.5 * np.median(theirs) + 1e-8, (ours, theirs)


def test_numpy_engine_is_reproducible_and_seeded():
    f = _functions()["rosenbrock"]
    a = get_optimizer("cmaes_numpy").minimize(f, 5, seed=7, budget=600)
    b = get_optimizer("cmaes_numpy").minimize(f, 5, seed=7, budget=600)
    c = get_optimizer("cmaes_numpy").minimize(f, 5, seed=8, budget=600)
    assert a.fun == b.fun and np.array_equal(a.x, b.x) and a.trace == b.trace
    assert not np.array_equal(a.x, c.x)


def test_a_flat_objective_stops_the_run_and_restarts():
    es = CMAState(np.full(3, 0.5), 0.2, popsize=6, rng=np.random.default_rng(0))
    es.ask()
    es.tell(np.zeros(6))
    assert es.stop() and es.stop_reason == "flat fitness"
    r = get_optimizer("cmaes_numpy").minimize(lambda u: np.zeros(len(u)), 3, seed=0, budget=400)
    assert r.restarts >= 1 and r.n_evals <= 400


def test_tell_needs_ask_and_engine_is_checked():
    es = CMAState(np.full(2, 0.5), 0.2, popsize=4, rng=np.random.default_rng(0))
    with pytest.raises(RuntimeError, match="before ask"):
        es.tell(np.zeros(4))
    with pytest.raises(ValueError, match="engine"):
        CMAES(engine="torch")
    assert get_optimizer("cmaes_numpy").engine == "numpy" and get_optimizer("cmaes").engine == "pycma"
