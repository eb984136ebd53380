"""Fitting Θ: recovery of a known Θ* for every distance, determinism, resume, parallel, Dask, bad inputs."""

import json
import math
import multiprocessing as mp
import os
import time
from pathlib import Path

import numpy as np
import pytest
import torch

from synthaug.data.procedural import sky_backgrounds
from synthaug.data.seedset import write_seedset
from synthaug.distances import list_distances
from synthaug.fit.fitting import FitConfig, build_distance, fit_one, fit_seedset, patches_tensor
from synthaug.fit.objective import FitSpace, RenderObjective
from synthaug.fit.optimizers import get_optimizer
from synthaug.params import CaptureParams

THETA_STAR = {"alpha": 0.4, "beta": 0.9, "gamma": 0.5, "t_x": 0.06, "t_y": -0.04, "sigma_s": 0.8,
              "sigma_u": 1.5, "sigma_v": 0.6, "alpha_m": 0.3, "sigma_n": 0.02, "w_d": 0.15}


@pytest.fixture(scope="module")
def fit_cache():
    """10° views: coarser grids make the objective piecewise constant in (α, β) over wide plateaus."""
    from synthaug.render.cache import ViewCache

    return ViewCache.build("quadcopter", step_deg=10, sprite_size=48)


@pytest.fixture(scope="module")
def measured(fit_cache):
    """A 'measured' seed X = S(Θ*, B) rendered through the same model (known truth)."""
    bg = patches_tensor(sky_backgrounds(1, (40, 40), seed=4))
    space = FitSpace.default()
    theta = CaptureParams(THETA_STAR)
    obj = RenderObjective(bg, bg, fit_cache, None, space, object_scale=0.7, noise_seed=11)
    x = obj.render(space.from_theta(theta))
    return x, bg, space, theta


def _seedset(tmp_path, n=4, seed=0, negatives=True):
    """A small seed set on disk made by the generator (objects are dark blobs)."""
    rng = np.random.default_rng(seed)
    bgs = sky_backgrounds(n, (40, 40), seed=seed)
    patches = bgs.copy()
    for i in range(n):
        yy, xx = np.mgrid[:40, :40]
        blob = ((xx - 20 - rng.integers(-3, 4)) ** 2 / 60 + (yy - 20) ** 2 / 12) < 1
        patches[i][blob] = 40
    frames = sky_backgrounds(n, (80, 80), seed=seed + 1)
    neg = sky_backgrounds(8, (40, 40), seed=seed + 2) if negatives else np.zeros((0, 40, 40), np.uint8)
    path = tmp_path / f"seeds{seed}"
    write_seedset(path, patches=patches, backgrounds=bgs, boxes=[[20, 20, 28, 14]] * n, centres=[[34, 27]] * n,
                  crops=[[34, 27, 40]] * n, records=[{"video": f"v{i}", "frame": i} for i in range(n)],
                  frames=list(frames), background_frames=list(frames), negatives=neg,
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    return path


def _distance_for(name, x, bg, cache, space):
    if name in ("wl_learned", "cnn"):
        # trained on seeds like X (renders at random Θ) against background crops
        g = torch.Generator().manual_seed(0)
        rand = CaptureParams.sample(48, generator=g)
        obj = RenderObjective(bg, bg, cache, None, space, object_scale=0.7, noise_seed=3)
        pos = obj.render(space.from_theta(rand))
        neg = patches_tensor(sky_backgrounds(48, (40, 40), seed=9))
        kw = {"positives": pos, "negatives": neg, "seed": 0}
        if name == "cnn":
            kw["epochs"] = 8
        return build_distance(name, **kw)
    if name == "wl_random":
        return build_distance(name, reference=torch.cat([x, bg]), seed=0)
    return build_distance(name)


DISTANCES = ["eucl", "hog", "wl_random", "wl_learned", "cnn"]


@pytest.mark.slow
@pytest.mark.parametrize("name", DISTANCES)
def test_recovers_capture_parameters_and_position(measured, fit_cache, name):
    """Known Θ*, rotations given (as the paper's annotated pose would), everything else fitted from random."""
    x, bg, _, theta = measured
    space = FitSpace.default(fixed={k: THETA_STAR[k] for k in ("alpha", "beta", "gamma")}, bounds={"sigma_n": (0, 0.1)})
    d = _distance_for(name, x, bg, fit_cache, space)
    res = fit_one(x, bg, fit_cache, d, FitConfig(distance=name, budget=800, fit_scale=False), seed=5,
                  object_scale=0.7, space=space)
    obj = RenderObjective(x, bg, fit_cache, d, space, object_scale=0.7, noise_seed=5)
    truth = obj(space.from_theta(theta))[0]  # > 0 only through the other noise draw
    rand = np.median(obj(np.random.default_rng(0).random((64, space.dim))))
    assert res["distance"] <= truth + 0.15 * (rand - truth), (name, res["distance"], truth, rand)
    fitted = CaptureParams.from_vector(torch.tensor([res["theta"]]), validate=False)
    # weak learners pool gradient energy over rectangles: a shift of 1-3 px barely changes them, and
    # random ones (thresholds not chosen for the object) do not pin the position at all: measured, a
    # 7 px error reached the truth's distance. Position is identifiable for the other four.
    if name == "wl_random":
        return
    tol = 0.1 if name.startswith("wl_") else 0.03
    assert abs(float(fitted.t_x) - THETA_STAR["t_x"]) < tol and abs(float(fitted.t_y) - THETA_STAR["t_y"]) < tol
    if name == "eucl":  # intensity is identifiable in pixel space
        assert abs(float(fitted.w_d) - THETA_STAR["w_d"]) < 0.06


@pytest.mark.slow
@pytest.mark.parametrize("name", ["eucl", "hog"])
def test_full_fit_from_a_random_start_improves_far_beyond_random(measured, fit_cache, name):
    """All of Θ free. Known weakness: the rotation is often not recovered (see the issue note)."""
    x, bg, space, theta = measured
    d = _distance_for(name, x, bg, fit_cache, space)
    res = fit_one(x, bg, fit_cache, d, FitConfig(distance=name, budget=2000, fit_scale=False, bounds={}), seed=5,
                  object_scale=0.7)
    obj = RenderObjective(x, bg, fit_cache, d, space, object_scale=0.7, noise_seed=5)
    truth = obj(space.from_theta(theta))[0]
    rand = np.median(obj(np.random.default_rng(0).random((64, space.dim))))
    assert res["distance"] <= truth + 0.75 * (rand - truth), (res["distance"], truth, rand)
    fitted = CaptureParams.from_vector(torch.tensor([res["theta"]]), validate=False)
    assert abs(float(fitted.t_x) - THETA_STAR["t_x"]) < 0.1 and abs(float(fitted.t_y) - THETA_STAR["t_y"]) < 0.1


def test_optimizers_keep_the_budget_and_improve_on_the_start(measured, fit_cache):
    """Behaviour only. Which optimiser is better at equal budget is a quality comparison, measured by
    ``benchmarks/bench_fit.py`` (CMA-ES vs the paper's annealing, and vs 10x-budget annealing)."""
    x, bg, space, _ = measured
    obj = RenderObjective(x, bg, fit_cache, build_distance("hog"), space, object_scale=0.7, noise_seed=11)
    x0 = np.random.default_rng(1).random(space.dim)
    start = float(obj(x0[None])[0])
    for name in ("cmaes", "anneal"):
        res = get_optimizer(name).minimize(obj, space.dim, x0=x0, seed=1, budget=150)
        assert 0 < res.n_evals <= 150, (name, res.n_evals)
        assert res.fun <= start, (name, res.fun, start)
        assert res.trace[-1][1] == pytest.approx(res.fun), name
        assert all(b <= a for (_, a), (_, b) in zip(res.trace, res.trace[1:])), name  # best-so-far trace


def test_fit_is_deterministic(measured, fit_cache):
    small_cache = fit_cache
    x, bg, _, _ = measured
    d = build_distance("hog")
    cfg = FitConfig(budget=300)
    a = fit_one(x, bg, small_cache, d, cfg, seed=3, object_scale=0.7)
    b = fit_one(x, bg, small_cache, d, cfg, seed=3, object_scale=0.7)
    assert a["theta"] == b["theta"] and a["distance"] == b["distance"]


def _small_cfg(**kw):
    return FitConfig(budget=kw.pop("budget", 120), step_deg=30, sprite_size=48, **kw)


def test_fit_seedset_file_and_dataset_reads_it(tmp_path):
    seeds = _seedset(tmp_path)
    out = fit_seedset(seeds, "quadcopter", tmp_path / "fit.json", _small_cfg())
    doc = json.loads(out.read_text())
    assert doc["format"] == "synthaug.capture_params" and doc["metadata"]["result_format"] == "synthaug.fit"
    assert len(doc["rows"]) == 4
    e = doc["rows"][2]["extra"]
    assert e["seed_index"] == 2 and e["video"] == "v2" and e["distance"] >= 0 and e["optimizer"]["n_evals"] <= 120
    assert not (tmp_path / ".fit.json.parts").exists()
    from synthaug.data.seedset import SeedSet
    from synthaug.data.synthetic import SyntheticObjectDataset

    ds = SyntheticObjectDataset("quadcopter", SeedSet.load(seeds), out, length=4,
                                render={"step_deg": 30, "sprite_size": 48})
    img, t = ds[0]
    row = CaptureParams.load(out)[int(t["seed_index"])].to_vector()[0]
    torch.testing.assert_close(t["theta"][5:], row[5:])


def _killed_run(seeds, out):
    # two seeds per lockstep group: parts land two at a time, so the kill can fall between them
    fit_seedset(seeds, "quadcopter", out, _small_cfg(budget=400), lockstep=2)


@pytest.mark.slow
def test_resume_after_kill_gives_the_same_file(tmp_path):
    seeds = _seedset(tmp_path, n=6)
    ref = fit_seedset(seeds, "quadcopter", tmp_path / "ref.json", _small_cfg(budget=400))
    out = tmp_path / "resumed.json"
    proc = mp.get_context("spawn").Process(target=_killed_run, args=(seeds, out))
    proc.start()
    parts = tmp_path / ".resumed.json.parts"
    deadline = time.time() + 120
    while time.time() < deadline and len(list(parts.glob("seed_*.json"))) < 2:
        time.sleep(0.05)
    proc.kill()
    proc.join()
    done = len(list(parts.glob("seed_*.json")))
    assert 1 <= done < 6, f"the kill came too late to test resume ({done} seeds done)"
    assert not out.exists()
    fit_seedset(seeds, "quadcopter", out, _small_cfg(budget=400))
    assert out.read_text() == ref.read_text()


@pytest.mark.slow
def test_parallel_processes_give_the_same_file(tmp_path):
    seeds = _seedset(tmp_path)
    a = fit_seedset(seeds, "quadcopter", tmp_path / "a.json", _small_cfg())
    b = fit_seedset(seeds, "quadcopter", tmp_path / "b.json", _small_cfg(), workers=2)
    assert a.read_text() == b.read_text()


@pytest.mark.slow
def test_dask_local_cluster_on_loopback(tmp_path):
    distributed = pytest.importorskip("distributed")
    seeds = _seedset(tmp_path)
    ref = fit_seedset(seeds, "quadcopter", tmp_path / "ref.json", _small_cfg())
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        out = fit_seedset(seeds, "quadcopter", tmp_path / "dask.json", _small_cfg(), dask_address=cluster.scheduler_address)
    assert out.read_text() == ref.read_text()


def test_bad_inputs(tmp_path):
    seeds = _seedset(tmp_path, negatives=False)
    with pytest.raises(FileNotFoundError):
        fit_seedset(tmp_path / "no_such_seeds", "quadcopter", tmp_path / "x.json", _small_cfg())
    with pytest.raises(ValueError, match="unknown distance 'nope'"):
        fit_seedset(seeds, "quadcopter", tmp_path / "x.json", _small_cfg(distance="nope"))
    with pytest.raises(ValueError, match="needs negatives"):
        fit_seedset(seeds, "quadcopter", tmp_path / "x.json", _small_cfg(distance="wl_learned"))
    with pytest.raises(FileNotFoundError, match="mesh file not found"):
        fit_seedset(seeds, tmp_path / "missing.glb", tmp_path / "x.json", _small_cfg())
    with pytest.raises(ValueError, match="unknown optimizer"):
        FitConfig(optimizer="sgd")
    with pytest.raises(ValueError, match="out of range"):
        fit_seedset(seeds, "quadcopter", tmp_path / "x.json", _small_cfg(), indices=[7])
    bad = tmp_path / "fit.json"
    CaptureParams.default(3).save(bad)
    from synthaug.data.seedset import SeedSet
    from synthaug.fit.render_fit import render_fitted

    with pytest.raises(ValueError, match="3 rows but the seed set has 4 seeds"):
        render_fitted(SeedSet.load(seeds), bad)


def test_fit_cli(tmp_path, capsys):
    from synthaug.cli import main

    seeds = _seedset(tmp_path)
    rc = main(["fit", "--seeds", str(seeds), "--out", str(tmp_path / "f.json"), "--budget", "60", "--no-progress",
               "--distance", "eucl", "--step-deg", "30", "--sprite-size", "48"])
    assert rc == 0
    assert json.loads(capsys.readouterr().out)["seeds"] == 4
    assert main(["fit", "--seeds", str(tmp_path / "nothing"), "--out", str(tmp_path / "g.json")]) == 2


# ------------------------------------------------------------ structured pose initialisation (init="grid")
def _sym_err_deg(theta_a, theta_b, order=4):
    """Rotation angle (deg) between two (α, β, γ), the minimum over ``order`` turns about the object's up axis."""
    from scipy.spatial.transform import Rotation

    ra = Rotation.from_euler("ZYX", [theta_a[2], theta_a[1], theta_a[0]])
    rb = Rotation.from_euler("ZYX", [theta_b[2], theta_b[1], theta_b[0]])
    return min(np.degrees((ra.inv() * rb * Rotation.from_euler("z", 2 * math.pi * k / order)).magnitude())
               for k in range(order))


def test_rotation_grid_covers_so3():
    from scipy.spatial.transform import Rotation

    from synthaug.fit.objective import rotation_grid

    grid, spacing = rotation_grid(240)
    assert 200 <= len(grid) <= 260 and np.all(np.abs(grid[:, 1]) <= math.pi / 2 + 1e-12)
    g = Rotation.from_euler("ZYX", grid[:, ::-1])
    rand = Rotation.random(300, random_state=0)
    nearest = np.array([(g.inv() * r).magnitude().min() for r in rand])
    # every rotation lies within one spacing of the grid (a uniform grid: ~0.75 spacing), and no big gaps
    assert nearest.max() < spacing and np.median(nearest) < 0.6 * spacing
    with pytest.raises(ValueError, match="n >= 8"):
        rotation_grid(3)


def test_grid_stage_alone_finds_a_grid_pose(measured, fit_cache):
    """Target rendered at a grid rotation with everything else neutral: stage 1 alone must pick that pose."""
    from synthaug.fit.fitting import neutral_u, pose_grid_starts
    from synthaug.fit.objective import rotation_grid

    _, bg, _, _ = measured
    space = FitSpace.default(bounds={"sigma_n": (0.0, 0.1)}, scale_range=(0.25 * 0.7, 1.25 * 0.7))
    grid, _ = rotation_grid(120)
    pose = grid[37]  # an oblique view
    render = RenderObjective(bg, bg, fit_cache, None, space, object_scale=0.7, noise_seed=2)
    target = render.render(space.pose_to_u(pose[None], neutral_u(space, 0.7)))
    obj = RenderObjective(target, bg, fit_cache, build_distance("eucl"), space, object_scale=0.7, noise_seed=2)
    calls = []
    counted = lambda u: (calls.append(len(np.atleast_2d(u))), obj(u))[1]  # noqa: E731
    init = pose_grid_starts(counted, space, budget=120, object_scale=0.7, n_starts=3, grid_share=1.0, seed=0)
    assert init["grid_size"] == len(grid) and init["n_evals"] == sum(calls) <= 120
    assert init["fun"] == pytest.approx(0.0, abs=1e-9)
    best = space.to_theta(init["starts"][:1])
    found = [float(best.alpha), float(best.beta), float(best.gamma)]
    assert _sym_err_deg(found, pose) < 1.0, (found, pose)
    assert len(init["starts"]) == 3 and init["stds"].shape == (space.dim,)


def test_grid_init_recovers_the_rotation_within_budget(measured, fit_cache):
    """All of Θ free from no start: the grid init lands near the true rotation (up to the 4-fold symmetry)."""
    x, bg, _, _ = measured
    cfg = FitConfig(budget=800, fit_scale=False, init="grid")
    res = fit_one(x, bg, fit_cache, build_distance("hog"), cfg, seed=5, object_scale=0.7)
    st = res["stats"]
    assert st["n_evals"] <= 800 and st["init"]["n_evals"] <= int(0.35 * 800) and st["init"]["grid_size"] > 100
    assert all(b <= a for (_, a), (_, b) in zip(st["trace"], st["trace"][1:])) and st["trace"][-1][1] == res["distance"]
    err = _sym_err_deg(res["theta"][:3], [THETA_STAR[k] for k in ("alpha", "beta", "gamma")])
    assert err < 25.0, err
    again = fit_one(x, bg, fit_cache, build_distance("hog"), cfg, seed=5, object_scale=0.7)
    assert again["theta"] == res["theta"] and again["distance"] == res["distance"]


def test_grid_init_options_and_fallbacks(measured, fit_cache):
    x, bg, _, _ = measured
    with pytest.raises(ValueError, match="unknown init"):
        FitConfig(init="sobol")
    with pytest.raises(ValueError, match="init_fraction"):
        FitConfig(init="grid", init_fraction=1.0)
    with pytest.raises(ValueError, match="init_starts"):
        FitConfig(init_starts=0)
    d = build_distance("hog")
    # too small a budget for a grid: the uniform start, no grid record
    tiny = fit_one(x, bg, fit_cache, d, FitConfig(budget=40, init="grid"), seed=1, object_scale=0.7)
    assert "init" not in tiny["stats"] and tiny["stats"]["n_evals"] <= 40
    # a given start wins over the grid
    space = FitSpace.default(bounds={"sigma_n": (0, 0.1)})
    x0 = space.from_theta(CaptureParams(THETA_STAR))[0]
    res = fit_one(x, bg, fit_cache, d, FitConfig(budget=60, init="grid", fit_scale=False), seed=1,
                  object_scale=0.7, x0=x0, space=space)
    assert "init" not in res["stats"]
    # rotations given (fixed in the space): nothing for a pose grid to do
    fixed = FitSpace.default(fixed={k: THETA_STAR[k] for k in ("alpha", "beta", "gamma")})
    res = fit_one(x, bg, fit_cache, d, FitConfig(budget=60, init="grid", fit_scale=False), seed=1,
                  object_scale=0.7, space=fixed)
    assert "init" not in res["stats"] and res["stats"]["n_evals"] <= 60
    with pytest.raises(ValueError, match="starts must be"):
        get_optimizer("cmaes").minimize(lambda u: np.zeros(len(u)), 3, starts=np.zeros((1, 2)), budget=50)
    with pytest.raises(ValueError, match="rotation"):
        FitSpace.default(fixed={"alpha": 0.0}).pose_to_u(np.zeros((1, 3)), np.full(10, 0.5))


def test_cmaes_uses_given_starts():
    """Starts near the optimum of a two-basin function: CMA-ES (no uniform look) stays in that basin."""
    f = lambda u: np.minimum(((np.atleast_2d(u) - 0.2) ** 2).sum(1), ((np.atleast_2d(u) - 0.8) ** 2).sum(1) - 0.01)  # noqa: E731
    near = get_optimizer("cmaes").minimize(f, 2, seed=0, budget=200, starts=np.array([[0.21, 0.19]]),
                                           stds=np.array([0.02, 0.02]))
    assert np.allclose(near.x, 0.2, atol=1e-2) and near.n_evals <= 200


def test_fit_cli_init_grid(tmp_path, capsys):
    from synthaug.cli import main

    seeds = _seedset(tmp_path)
    rc = main(["fit", "--seeds", str(seeds), "--out", str(tmp_path / "f.json"), "--budget", "120", "--no-progress",
               "--distance", "eucl", "--step-deg", "30", "--sprite-size", "48", "--init", "grid"])
    assert rc == 0
    doc = json.loads((tmp_path / "f.json").read_text())
    assert doc["metadata"]["config"]["init"] == "grid"
    assert all(r["extra"]["optimizer"]["init"]["name"] == "grid" for r in doc["rows"])
    capsys.readouterr()
