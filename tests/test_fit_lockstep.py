"""Seeds fitted in lockstep (synthaug.fit.lockstep): the same values and fits as one at a time, errors stop all."""

import json

import numpy as np
import pytest
import torch

from synthaug.data.procedural import sky_backgrounds
from synthaug.fit.fitting import FitConfig, build_distance, fit_objective, fit_seedset, patches_tensor, search
from synthaug.fit.lockstep import run_lockstep
from synthaug.fit.objective import score_together
from synthaug.fit.optimizers import get_optimizer

from test_fit import _seedset, _small_cfg


@pytest.fixture(scope="module")
def cache():
    from synthaug.render.cache import ViewCache

    return ViewCache.build("quadcopter", step_deg=30, sprite_size=48)


def _objectives(cache, n=3, *, distance="hog", cfg=None, geometry=False):
    cfg = cfg or FitConfig()
    bgs = patches_tensor(sky_backgrounds(n, (40, 40), seed=3))
    g = torch.Generator().manual_seed(0)
    targets = (bgs + 0.2 * torch.rand(bgs.shape, generator=g)).clamp(0, 1)
    d = build_distance(distance, reference=torch.cat([targets, bgs]), seed=0) if distance == "wl_random" \
        else build_distance(distance)
    out = []
    for i in range(n):
        geo = None
        if geometry:
            geo = {"origin": torch.tensor([[10.0 * i, 5.0]]), "frame_size": torch.tensor([[320.0, 240.0]]),
                   "frame_scale": torch.tensor([0.8 + 0.3 * i])}
        out.append(fit_objective(targets[i:i + 1], bgs[i:i + 1], cache, d, cfg, seed=100 + i,
                                 object_scale=0.6 + 0.05 * i, geometry=geo))
    return out


@pytest.mark.parametrize("distance", ["hog", "eucl", "wl_random"])
def test_score_together_equals_separate_calls(cache, distance):
    # different noise fields, backgrounds, object scales; populations of different sizes, one empty; chunk
    # boundaries that fall inside a seed's population; wl_random overrides forward (the per-candidate targets path)
    objs = _objectives(cache, 3, distance=distance)
    for o in objs:
        o.chunk = 7
    rng = np.random.default_rng(1)
    us = [rng.random((n, o.space.dim)) for n, o in zip((5, 0, 12), objs)]
    together = score_together(objs, us)
    alone = [o(u) if len(u) else np.zeros(0) for o, u in zip(objs, us)]
    for a, b in zip(alone, together):
        assert a.shape == b.shape and np.array_equal(a, b)
    assert [o.n_evals for o in objs] == [10, 0, 24]


def test_score_together_measured_noise_and_camera_effects(cache):
    # per-seed fixed sigma_n (another search space each) and frame geometry for a position-aware effect
    cfg = FitConfig(object_noise="measured",
                    effects=("boundary_blur", "motion_blur", "object_noise", "material", "vignetting"))
    objs = _objectives(cache, 2, cfg=cfg, geometry=True)
    assert not np.array_equal(objs[0].space.fixed, objs[1].space.fixed)
    rng = np.random.default_rng(2)
    us = [rng.random((6, o.space.dim)) for o in objs]
    for a, b in zip([o(u) for o, u in zip(objs, us)], score_together(objs, us)):
        assert np.array_equal(a, b)


def test_score_together_refuses_objectives_that_cannot_share_a_batch(cache):
    a, b = _objectives(cache, 2)
    b.distance = build_distance("hog")
    with pytest.raises(ValueError, match="share one view cache and one distance"):
        score_together([a, b], [np.zeros((1, a.space.dim))] * 2)
    with pytest.raises(ValueError, match="2 objectives but 1 populations"):
        score_together([a, a], [np.zeros((1, a.space.dim))])


def test_run_lockstep_gives_the_fits_made_alone(cache):
    cfg = FitConfig(budget=150)
    alone = [search(o, cfg, seed=7 + k, object_scale=o.object_scale) for k, o in enumerate(_objectives(cache, 3))]
    objs = _objectives(cache, 3)
    together = run_lockstep(objs, [lambda ev, o=o, k=k: search(o, cfg, seed=7 + k, object_scale=o.object_scale,
                                                                  evaluate=ev) for k, o in enumerate(objs)])
    for a, b in zip(alone, together):
        assert a["theta"] == b["theta"] and a["distance"] == b["distance"]
        assert a["stats"]["n_evals"] == b["stats"]["n_evals"] <= 150
    assert sum(o.n_evals for o in objs) == sum(a["stats"]["n_evals"] for a in alone)


@pytest.mark.parametrize("optimizer", ["cmaes", "cmaes_pycma"])
def test_lockstep_fits_do_not_depend_on_thread_timing(cache, optimizer):
    """Random delays before each search's asks (another CPU load, a slow thread): the rounds' company changes
    timing only, every fit is still the one made alone (issue 19: scores are batch-invariant bit for bit)."""
    import random
    import time

    cfg = FitConfig(budget=150, optimizer=optimizer)
    alone = [search(o, cfg, seed=7 + k, object_scale=o.object_scale) for k, o in enumerate(_objectives(cache, 3))]
    rnd = random.Random(0)

    def late(ev):
        def f(u):
            time.sleep(rnd.random() * 0.002)
            return ev(u)
        return f

    for _ in range(2):
        objs = _objectives(cache, 3)
        together = run_lockstep(objs, [lambda ev, o=o, k=k: search(o, cfg, seed=7 + k, object_scale=o.object_scale,
                                                                      evaluate=late(ev)) for k, o in enumerate(objs)])
        for a, b in zip(alone, together):
            assert a["theta"] == b["theta"] and a["distance"] == b["distance"]


def test_run_lockstep_error_in_one_search_stops_all(cache):
    objs = _objectives(cache, 3)

    def failing(ev):
        ev(np.full((2, objs[1].space.dim), 0.5))
        raise RuntimeError("search 1 broke")

    def long(ev, o):
        for _ in range(10_000):  # would run for minutes if it were not stopped
            ev(np.full((4, o.space.dim), 0.5))

    with pytest.raises(RuntimeError, match="search 1 broke"):
        run_lockstep(objs, [lambda ev: long(ev, objs[0]), failing, lambda ev: long(ev, objs[2])])
    assert objs[0].n_evals < 100


@pytest.mark.parametrize("name", ["cmaes", "cmaes_pycma"])
def test_cmaes_leaves_numpys_global_generator_alone(name):
    # pycma draws from np.random unless given its own "randn": searches in threads must not share it
    np.random.seed(5)
    before = np.random.get_state()[1].copy()
    r1 = get_optimizer(name).minimize(lambda x: ((x - 0.3) ** 2).sum(1), 4, seed=3, budget=200)
    assert np.array_equal(np.random.get_state()[1], before)
    np.random.seed(99)
    r2 = get_optimizer(name).minimize(lambda x: ((x - 0.3) ** 2).sum(1), 4, seed=3, budget=200)
    assert np.array_equal(r1.x, r2.x) and r1.fun == r2.fun


def test_fit_seedset_same_file_whatever_the_lockstep(tmp_path):
    seeds = _seedset(tmp_path, n=5)
    files = [fit_seedset(seeds, "quadcopter", tmp_path / f"l{k}.json", _small_cfg(budget=150), lockstep=k)
             for k in (1, 2, 5)]
    rows = [json.loads(f.read_text())["rows"] for f in files]
    assert rows[0] == rows[1] == rows[2]
    with pytest.raises(ValueError, match="lockstep must be an int >= 1"):
        fit_seedset(seeds, "quadcopter", tmp_path / "x.json", _small_cfg(), lockstep=0)


def test_fit_cli_lockstep_option(tmp_path, capsys):
    from synthaug.cli import main

    seeds = _seedset(tmp_path, n=3)
    args = ["fit", "--seeds", str(seeds), "--budget", "60", "--no-progress", "--distance", "eucl", "--step-deg", "30",
            "--sprite-size", "48"]
    assert main([*args, "--out", str(tmp_path / "a.json"), "--lockstep", "1"]) == 0
    assert main([*args, "--out", str(tmp_path / "b.json"), "--lockstep", "3"]) == 0
    assert (json.loads((tmp_path / "a.json").read_text())["rows"]
            == json.loads((tmp_path / "b.json").read_text())["rows"])
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main([*args, "--out", str(tmp_path / "c.json"), "--lockstep", "0"])
