"""The numpy CMA-ES (synthaug.fit.optimizers.CMAState) against independent references: the ``cma`` package's
strategy constants, Hansen's tutorial formulas (arXiv:1604.00772, table 1) computed by hand, and the ``cma``
package's search on the same budgets (``CMAES(engine="pycma")``, ``cmaes_pycma``; the numpy engine is the default ``cmaes``)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from synthaug.fit.optimizers import CMAES, CMAState, from_unit_box, get_optimizer, to_unit_box

cma = pytest.importorskip("cma")


@pytest.mark.parametrize("n, lam", [(12, 12), (12, 24), (5, 9), (3, 48)])
def test_strategy_constants_equal_pycmas(n, lam):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = cma.CMAEvolutionStrategy(np.full(n, 0.5), 0.2, {"popsize": lam, "verbose": -9}).sp
    es = CMAState(np.full(n, 0.5), 0.2, popsize=lam, rng=np.random.default_rng(0))
    # recombination weights incl. the active (negative) ones, mu_eff and the learning rates: as pycma's
    np.testing.assert_allclose(es.weights, np.asarray(ref.weights), rtol=1e-12, atol=1e-15)
    for ours, theirs in ((es.mueff, ref.weights.mueff), (es.cc, ref.cc), (es.c1, ref.c1), (es.cmu, ref.cmu)):
        assert ours == pytest.approx(theirs, rel=1e-12)
    # step-size constants: pycma's (its c_sigma, its damping with the attenuated mu_eff term, its E||N(0, I)||)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        full = cma.CMAEvolutionStrategy(np.full(n, 0.5), 0.2, {"popsize": lam, "verbose": -9})
    from cma.utilities.math import Mh

    assert es.cs == pytest.approx(full.adapt_sigma.cs, rel=1e-12)
    assert es.damps == pytest.approx(full.adapt_sigma.damps, rel=1e-12)
    assert es.chin == pytest.approx(Mh.chiN(n), rel=1e-7)
    assert es.lazy_gap == pytest.approx(full.sm.lazy_update_gap, rel=1e-12)
    # and by hand (cma/sigma_adaptation.py, compute_cs / compute_damps with the module's defaults)
    me = es.mueff
    assert es.cs == pytest.approx(min(0.5, (me + 2) / (n + me + 3)))
    damp_in = max(1, 3 * (1 - 0.5 ** (n / 9)))
    assert es.damps == pytest.approx(1 + 2 * max(0, damp_in * math.sqrt((me - 1) / (n + 1)) - 1) + es.cs)
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
    assert abs(math.log10(w[-1] / w[0]) - 4) < 0.6  # the Hessian's condition, 1e4, within a factor 4
    assert abs(v[0, -1]) > 0.99  # the widest axis is the first (flat) coordinate
    assert np.allclose(to_unit_box(es.mean), 0.5, atol=1e-5)


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


def test_a_flat_objective_stops_the_run_after_two_flat_generations_and_restarts():
    """pycma's tolflatfitness (1): a generation whose best equals its 75th percentile is tolerated once."""
    es = CMAState(np.full(3, 0.5), 0.2, popsize=6, rng=np.random.default_rng(0))
    flat = np.r_[np.zeros(5), 1.0]  # the best equals the 75th percentile (the values not all equal: not tolfun)
    es.ask()
    es.tell(flat)
    assert not es.stop()
    es.ask()
    es.tell(np.r_[0.0, np.ones(5)])  # the best below the 75th percentile: the count starts again
    for _ in range(2):
        assert not es.stop()
        es.ask()
        es.tell(flat)
    assert es.stop() and es.stop_reason == "tolflatfitness"
    r = get_optimizer("cmaes_numpy").minimize(lambda u: np.zeros(len(u)), 3, seed=0, budget=400)
    assert r.restarts >= 1 and r.n_evals <= 400


def _pycma_and_ours(n, lam, seed, start, sigma0, stds, **opts):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = cma.CMAEvolutionStrategy(start, sigma0, {
            "bounds": [0.0, 1.0], "seed": float("nan"), "randn": np.random.RandomState(seed).randn, "popsize": lam,
            "verbose": -9, "tolfun": 1e-9, "tolx": 1e-7, "CMA_stds": list(stds), **opts})
    ours = CMAState(start, sigma0, popsize=lam, rng=np.random.RandomState(seed), stds=stds,
                    maxfevals=opts.get("maxfevals"))
    return ref, ours


@pytest.mark.parametrize("n, lam, seed, sigma0, std", [(6, 10, 5, 1.0, 0.15), (12, 12, 1, 1.0, 0.05),
                                                      (4, 24, 2, 2.0, 0.3)])
def test_given_pycmas_normal_stream_the_run_is_pycmas(n, lam, seed, sigma0, std):
    """Generation by generation, the candidates, mean, paths, covariance, step size and coordinate scales equal
    pycma's (up to rounding) on a tilted ellipsoid whose optimum lies near a bound; with sigma0 x std = 0.6 pycma's
    cap of every coordinate's standard deviation at a third of the box takes the scale down at the start."""
    def f(u):
        return (10 ** (2 * np.arange(n) / (n - 1)) * (u - 0.05) ** 2).sum(1) + 0.3 * u[:, 0]

    stds = np.linspace(std, 2 * std, n)
    ref, ours = _pycma_and_ours(n, lam, seed, np.full(n, 0.4), sigma0, stds)
    for g in range(60):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            x = np.asarray(ref.ask())
        y = ours.ask()
        np.testing.assert_allclose(y, x, rtol=0, atol=1e-9, err_msg=f"generation {g}")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ref.tell(list(x), list(f(x)))
        ours.tell(f(y))
        assert ours.sigma == pytest.approx(ref.sigma, rel=1e-8)
        np.testing.assert_allclose(ours.mean, ref.mean, rtol=0, atol=1e-9)
        np.testing.assert_allclose(ours.ps, ref.adapt_sigma.ps, rtol=0, atol=1e-7)
        np.testing.assert_allclose(ours.pc, ref.pc, rtol=0, atol=1e-7)
        np.testing.assert_allclose(ours.C, ref.sm.C, rtol=1e-7, atol=1e-12)
        np.testing.assert_allclose(ours.scale, ref.sigma_vec.scaling * np.ones(n), rtol=1e-10)
    if sigma0 * std > 1 / 3:
        assert (ours.scale < stds).any()  # the cap acted
    else:
        np.testing.assert_array_equal(ours.scale, stds)


@pytest.mark.parametrize("case", ["sphere", "plateaus", "maxfevals"])
def test_the_run_stops_when_and_why_pycma_stops(case):
    n, lam = 5, 8
    if case == "plateaus":  # flat generations: pycma's tolflatfitness
        f = lambda u: np.floor(((u - 0.3) ** 2).sum(1) * 4)  # noqa: E731
    else:
        f = lambda u: ((u - 0.3) ** 2).sum(1)  # noqa: E731
    extra = {"maxfevals": 100} if case == "maxfevals" else {}
    ref, ours = _pycma_and_ours(n, lam, 3, np.full(n, 0.6), 1.0, np.full(n, 0.2), **extra)
    for g in range(2000):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            x = np.asarray(ref.ask())
            ref.tell(list(x), list(f(x)))
        ours.tell(f(ours.ask()))
        if ref.stop() or ours.stop():
            break
    assert ours.stop() and ref.stop(), (g, ref.stop(), ours.stop_reason)
    assert ours.stop_reason in ref.stop()
    assert ours.gen == ref.countiter
    assert ours.stop_reason == {"sphere": "tolfun", "plateaus": "tolflatfitness", "maxfevals": "maxfevals"}[case] or \
        case == "sphere" and ours.stop_reason in ("tolx", "tolfunhist")


@pytest.mark.parametrize("name", ["sphere", "ellipsoid", "on_bound"])
def test_the_numpy_engine_makes_pycmas_search(name):
    """The whole search (restarts, given starts, per-coordinate steps): the same evaluations, restarts and best
    point as with pycma, up to rounding — the engines share the normal stream of each run."""
    f = _functions()[name]
    d = 8
    for seed in range(3):
        starts = np.random.default_rng(100 + seed).random((3, d))
        kw = dict(seed=seed, budget=1500, starts=starts, stds=np.full(d, 0.15))
        a = CMAES(engine="numpy").minimize(f, d, **kw)
        b = CMAES(engine="pycma").minimize(f, d, **kw)
        assert (a.n_evals, a.restarts, len(a.trace)) == (b.n_evals, b.restarts, len(b.trace))
        np.testing.assert_allclose(a.x, b.x, atol=1e-9)
        assert a.fun == pytest.approx(b.fun, rel=1e-6, abs=1e-12)


def test_tell_needs_ask_and_engine_is_checked():
    es = CMAState(np.full(2, 0.5), 0.2, popsize=4, rng=np.random.default_rng(0))
    with pytest.raises(RuntimeError, match="before ask"):
        es.tell(np.zeros(4))
    with pytest.raises(ValueError, match="engine"):
        CMAES(engine="torch")
    assert get_optimizer("cmaes").engine == "numpy" and get_optimizer("cmaes_pycma").engine == "pycma"
    assert get_optimizer("cmaes_numpy").engine == "numpy"  # the former name, one release
