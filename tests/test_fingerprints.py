"""Fingerprints of everything that changes a result (issue 18): an interrupted ``fit`` rerun with other inputs
recomputes its parts and says why; with the same inputs it reuses them and gives the uninterrupted file; an edited
label file re-ingests exactly its video; a rerun with other videos does not report an old seed set as current."""

from __future__ import annotations

import json
import logging
import os
import shutil

import numpy as np
import pytest

from synthaug.data.procedural import sky_backgrounds
from synthaug.data.seedset import write_seedset
from synthaug.fit.fitting import FitConfig, fit_seedset

N = 4


def _seedset(root, seed=0):
    """A small seed set on disk (dark blobs on generated skies), as tests/test_fit.py."""
    rng = np.random.default_rng(seed)
    bgs = sky_backgrounds(N, (40, 40), seed=seed)
    patches = bgs.copy()
    for i in range(N):
        yy, xx = np.mgrid[:40, :40]
        blob = ((xx - 20 - rng.integers(-3, 4)) ** 2 / 60 + (yy - 20) ** 2 / 12) < 1
        patches[i][blob] = 40
    frames = sky_backgrounds(N, (80, 80), seed=seed + 1)
    path = root / f"seeds{seed}"
    write_seedset(path, patches=patches, backgrounds=bgs, boxes=[[20, 20, 28, 14]] * N, centres=[[34, 27]] * N,
                  crops=[[34, 27, 40]] * N, records=[{"video": f"v{i}", "frame": i} for i in range(N)],
                  frames=list(frames), background_frames=list(frames),
                  negatives=sky_backgrounds(8, (40, 40), seed=seed + 2),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    return path


def _cfg(**kw):
    kw.setdefault("budget", 60)
    return FitConfig(step_deg=30, sprite_size=48, **kw)


class _Stop(KeyboardInterrupt):
    pass


def _interrupted(seeds, out, cfg, after=2):
    """A run stopped (as by Ctrl-C) once ``after`` seeds are finished: their parts stay, no output file."""
    def progress(done, total):
        if done >= after:
            raise _Stop()

    with pytest.raises(_Stop):
        fit_seedset(seeds, "quadcopter", out, cfg, progress=progress)
    parts = out.parent / f".{out.name}.parts"
    assert len(list(parts.glob("seed_*.json"))) == after and not out.exists()
    return parts


def _rerun(seeds, out, cfg):
    """Rerun; returns how many seeds it fitted (the progress calls)."""
    calls = []
    fit_seedset(seeds, "quadcopter", out, cfg, progress=lambda d, t: calls.append(d))
    return len(calls)


@pytest.fixture(scope="module")
def fit_world(tmp_path_factory):
    root = tmp_path_factory.mktemp("fp")
    seeds, other = _seedset(root, 0), _seedset(root, 5)
    refs = {}
    for name, s, cfg in [("hog60", seeds, _cfg()), ("eucl60", seeds, _cfg(distance="eucl")),
                         ("hog40", seeds, _cfg(budget=40)), ("other60", other, _cfg())]:
        refs[name] = fit_seedset(s, "quadcopter", root / f"ref_{name}.json", cfg).read_text()
    return root, seeds, other, refs


def _warnings(caplog):
    return [r.getMessage() for r in caplog.records if r.name == "synthaug.fit" and r.levelno >= logging.WARNING]


@pytest.mark.parametrize("change", ["distance", "budget", "seedset"])
def test_interrupted_fit_rerun_with_other_inputs_recomputes_and_says_why(fit_world, tmp_path, caplog, change):
    root, seeds, other, refs = fit_world
    out = tmp_path / "fit.json"
    _interrupted(seeds, out, _cfg())
    new_seeds, cfg, ref, why = {
        "distance": (seeds, _cfg(distance="eucl"), "eucl60", 'distance "hog" -> "eucl"'),
        "budget": (seeds, _cfg(budget=40), "hog40", "budget 60 -> 40"),
        "seedset": (other, _cfg(), "other60", "the seed set's content"),
    }[change]
    caplog.set_level(logging.WARNING, logger="synthaug.fit")
    assert _rerun(new_seeds, out, cfg) == N  # every seed fitted again, none reused
    msgs = _warnings(caplog)
    assert any("recomputing 2 finished seed(s)" in m and why in m for m in msgs), msgs
    assert out.read_text() == refs[ref]
    meta = json.loads(out.read_text())["metadata"]
    assert meta["config"]["budget"] == cfg.budget and meta["config"]["distance"] == cfg.distance


def test_interrupted_fit_rerun_with_the_same_inputs_reuses_parts_byte_identical(fit_world, tmp_path, caplog):
    root, seeds, _, refs = fit_world
    out = tmp_path / "fit.json"
    _interrupted(seeds, out, _cfg())
    caplog.set_level(logging.WARNING, logger="synthaug.fit")
    assert _rerun(seeds, out, _cfg()) == N - 2  # the two finished seeds are reused
    assert _warnings(caplog) == []
    assert out.read_text() == refs["hog60"]
    assert not (tmp_path / ".fit.json.parts").exists()


def test_parts_without_or_with_a_foreign_fingerprint_are_recomputed(fit_world, tmp_path, caplog):
    root, seeds, _, refs = fit_world
    out = tmp_path / "fit.json"
    parts = _interrupted(seeds, out, _cfg())
    p0, p1 = sorted(parts.glob("seed_*.json"))
    doc = json.loads(p0.read_text())
    for k in ("fingerprint", "inputs"):  # as written by an older synthaug
        doc.pop(k)
    p0.write_text(json.dumps(doc))
    p1.write_text("{truncated")
    caplog.set_level(logging.WARNING, logger="synthaug.fit")
    assert _rerun(seeds, out, _cfg()) == N
    msgs = " | ".join(_warnings(caplog))
    assert "older synthaug" in msgs and "unreadable" in msgs
    assert out.read_text() == refs["hog60"]


def test_a_given_distance_object_is_part_of_the_fingerprint(fit_world, tmp_path, caplog):
    from synthaug.distances import get_distance
    from synthaug.fit.fitting import fit_inputs, object_digest

    root, seeds, _, _ = fit_world
    a, b = get_distance("wl_random", seed=0), get_distance("wl_random", seed=1)
    assert object_digest(a) == object_digest(get_distance("wl_random", seed=0))
    assert object_digest(a) != object_digest(b)
    assert fit_inputs(seeds, "quadcopter", _cfg(), a) != fit_inputs(seeds, "quadcopter", _cfg(), b)
    assert "distance_object" not in fit_inputs(seeds, "quadcopter", _cfg())


def test_mesh_file_bytes_are_part_of_the_fingerprint(fit_world, tmp_path):
    from synthaug.fit.fitting import fit_inputs, what_changed

    root, seeds, _, _ = fit_world
    m = tmp_path / "m.obj"
    m.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    a = fit_inputs(seeds, m, _cfg())
    m.write_text("v 0 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\n")
    b = fit_inputs(seeds, m, _cfg())
    assert what_changed(a, b) == "the mesh"
    assert fit_inputs(seeds, "quadcopter", _cfg())["mesh_sha256"] == "builtin:quadcopter"
