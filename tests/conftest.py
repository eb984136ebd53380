from __future__ import annotations

import os
from collections import Counter
from pathlib import Path

import pytest

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")


def _share_the_cores_between_xdist_workers() -> None:
    """Under ``pytest -n N`` give each worker its share of the cores (torch, OpenMP, BLAS and the subprocesses tests
    start). Each worker's torch would otherwise spin as many threads as the machine has cores, N times over: on a
    2-core machine (stop 54) ``tests/test_demo.py tests/test_gap.py -n 2`` took 5 min 29 s (user 8 min 7 s) with the
    default threads and 4 min 47 s (user 5 min 23 s) with one thread a worker; test_speckle_is_detected[hog] 65 s ->
    6 s."""
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "0") or 0)
    if workers <= 1:
        return
    if "OMP_NUM_THREADS" in os.environ:  # the user's own setting stands (torch reads it)
        return
    share = max(1, (os.cpu_count() or 1) // workers)
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ.setdefault(var, str(share))
    import torch

    torch.set_num_threads(share)


_share_the_cores_between_xdist_workers()


def pytest_collection_modifyitems(config, items):
    """The modules holding the most ``slow`` tests first, each module's tests kept together and in their order.

    Under ``pytest -n 2 --dist worksteal`` (the README's test command) the workers start on the two halves of this
    order and an idle worker takes half of the other's remaining queue, so the suite's end is bounded by the test
    running last: with the long ones first it is a short one. Keeping a module's tests together keeps its
    module-scoped fixtures (a trained detector, a fitted seed set, the demo's run) built once per worker.
    """
    slow = Counter(item.path for item in items if item.get_closest_marker("slow") is not None)
    items.sort(key=lambda item: -slow[item.path])  # stable: the collection order within a count

REPO = Path(__file__).resolve().parents[1]
SHARED = (REPO / ".." / "shared").resolve()
SHARED_DATA = SHARED / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """../shared/data, or a clear skip when it is absent."""
    if not (SHARED_DATA / "README.md").exists():
        pytest.skip(f"real data not found at {SHARED_DATA} (clone ../shared beside the repo to run this test)")
    return SHARED_DATA


@pytest.fixture(scope="session", autouse=True)
def _private_view_cache(tmp_path_factory):
    """Keep the tests' view-cache sprites out of the user's ~/.cache."""
    old = os.environ.get("SYNTHAUG_CACHE")
    os.environ["SYNTHAUG_CACHE"] = str(tmp_path_factory.mktemp("synthaug_cache"))
    yield
    if old is None:
        os.environ.pop("SYNTHAUG_CACHE", None)
    else:
        os.environ["SYNTHAUG_CACHE"] = old


@pytest.fixture(scope="session")
def bench_null():
    """``benchmarks/bench_diagnose_null.py`` as a module: the null/power benchmark's case maker and bookkeeping."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_diagnose_null", REPO / "benchmarks" / "bench_diagnose_null.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="session")
def small_cache():
    """A coarse view cache of the built-in quadcopter (30° grid, 48 px sprites)."""
    from synthaug.render.cache import ViewCache

    return ViewCache.build("quadcopter", step_deg=30, sprite_size=48)


@pytest.fixture
def effect_registry(monkeypatch):
    """The effect registry, restored after the test: an effect a test registers does not leak into others.

    Returns the :mod:`synthaug.effects.registry` module; ``register_effect`` writes into a copy of its
    table, and the parameters it declares to :mod:`synthaug.params` are taken back afterwards.
    """
    from synthaug import params
    from synthaug.effects import registry

    monkeypatch.setattr(registry, "_REGISTRY", dict(registry._REGISTRY))
    declared = dict(params._DECLARED)
    try:
        yield registry
    finally:
        params._DECLARED.clear()
        params._DECLARED.update(declared)
