from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

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
