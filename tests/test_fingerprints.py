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

    with pytest.raises(_Stop):  # one seed at a time: parts land one by one (lockstep groups land together)
        fit_seedset(seeds, "quadcopter", out, cfg, progress=progress, lockstep=1)
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



def test_the_optimiser_implementation_is_part_of_the_fingerprint(fit_world):
    """A fit made by another implementation of the optimiser (the numpy CMA-ES vs the cma package's, or an older
    numpy engine) visits other points: it is not reused, and the warning says why."""
    from synthaug.fit.fitting import fit_inputs, what_changed
    from synthaug.fit.optimizers import CMASTATE_VERSION, IMPLEMENTATION_VERSION

    root, seeds, _, _ = fit_world
    a = fit_inputs(seeds, "quadcopter", _cfg(optimizer="cmaes_pycma"))
    b = fit_inputs(seeds, "quadcopter", _cfg())  # the default: the numpy engine
    assert a["optimizer"].startswith(f"synthaug cmaes_pycma {IMPLEMENTATION_VERSION} (pycma")
    assert f"numpy CMAState {CMASTATE_VERSION})" in b["optimizer"] and "CMAState" not in a["optimizer"]
    # the numpy engine's own version: a fit of an older numpy engine is recomputed, a pycma fit's key is untouched
    older_numpy = dict(b, optimizer=b["optimizer"].replace(f"CMAState {CMASTATE_VERSION})", "CMAState)"))
    assert what_changed(older_numpy, b).startswith("the optimiser's implementation")
    assert what_changed(a, b).startswith('optimizer "cmaes_pycma" -> "cmaes", the optimiser\'s implementation')
    older = dict(a, optimizer=a["optimizer"].replace(f" {IMPLEMENTATION_VERSION} ", " 1 "))
    assert what_changed(older, a).startswith("the optimiser's implementation synthaug cmaes_pycma 1")

# ------------------------------------------------------------------------ ingest
from synthaug.data.ingest import IngestConfig, ingest_videos  # noqa: E402
from synthaug.data.seedset import SeedSet  # noqa: E402
from synthaug.data.synthvideo import make_panning_video  # noqa: E402

ICFG = IngestConfig(seeds_per_video=3, negatives_per_video=4, hard_negatives_per_video=3, patch_size=24,
                    colour=False)


@pytest.fixture(scope="module")
def videos(tmp_path_factory):
    """Two folders of generated videos: ``a`` (drones 1-3) and ``b`` (the same names, other films, plus drone 4)."""
    root = tmp_path_factory.mktemp("vids")
    for k in range(3):
        make_panning_video(root / "a", n_frames=24, size=(192, 144), seed=10 + k, name=f"V_DRONE_{k + 1:03d}")
    for k in range(4):
        make_panning_video(root / "b", n_frames=24, size=(192, 144), seed=40 + k, name=f"V_DRONE_{k + 1:03d}")
    return root


def _ingest(root, out, **kw):
    kw.setdefault("cfg", ICFG)
    kw.setdefault("workers", 1)
    kw.setdefault("progress", False)
    kw.setdefault("seed_counts", (3,))
    return ingest_videos(root / "videos", root / "labels", out, **kw)


def _ingest_warnings(caplog):
    return [r.getMessage() for r in caplog.records if r.name == "synthaug.ingest" and r.levelno >= logging.WARNING]


def test_editing_one_label_file_reingests_exactly_that_video(videos, tmp_path, caplog):
    root = tmp_path / "a"
    shutil.copytree(videos / "a", root)
    out = tmp_path / "out"
    first = _ingest(root, out)
    assert first["processed"] == 3 and first["redone"] == {}
    shard1 = (out / "pool/V_DRONE_001/arrays.npz").read_bytes()
    # a user corrects the boxes of video 2 (shifted by 2 px)
    lab = root / "labels/V_DRONE_002.json"
    doc = json.loads(lab.read_text())
    doc["boxes"] = [None if b is None else [b[0] + 2, b[1], b[2], b[3]] for b in doc["boxes"]]
    lab.write_text(json.dumps(doc))
    caplog.set_level(logging.WARNING, logger="synthaug.ingest")
    again = _ingest(root, out)
    assert again["processed"] == 1 and list(again["videos"]) == ["V_DRONE_002"]
    assert again["skipped_current"] == 2 and again["redone"] == {"V_DRONE_002": "the label file"}
    assert any("V_DRONE_002: the label file changed" in m for m in _ingest_warnings(caplog))
    assert (out / "pool/V_DRONE_001/arrays.npz").read_bytes() == shard1  # the others untouched
    boxes = {r["frame"]: r["box"] for r in SeedSet.load(out / "pool/V_DRONE_002").records}
    for t, b in boxes.items():
        assert b[0] == pytest.approx(doc["boxes"][t][0], abs=0.01)
    seeds = SeedSet.load(out / "seedsets/drone_3")
    for r in seeds.records:
        if r["video"] == "V_DRONE_002":
            assert r["box"][0] == pytest.approx(doc["boxes"][r["frame"]][0], abs=0.01)
    # unchanged inputs: nothing redone, same seed set
    caplog.clear()
    third = _ingest(root, out)
    assert third["processed"] == 0 and third["skipped_current"] == 3 and _ingest_warnings(caplog) == []


def test_a_replaced_video_or_another_split_reingests_it(videos, tmp_path):
    root = tmp_path / "a"
    shutil.copytree(videos / "a", root)
    out = tmp_path / "out"
    first = _ingest(root, out, seed_counts=())
    # new time stamps on the same bytes (a copied data folder): every shard is current
    for f in (*root.glob("videos/*"), *root.glob("labels/*")):
        os.utime(f, ns=(f.stat().st_atime_ns, f.stat().st_mtime_ns + 10**12))
    touched = _ingest(root, out, seed_counts=())
    assert list(touched["videos"]) == [] and touched["skipped_current"] == len(first["videos"]) > 0, touched
    shutil.copy2(videos / "b/videos/V_DRONE_003.mp4", root / "videos/V_DRONE_003.mp4")
    again = _ingest(root, out, seed_counts=())
    assert list(again["videos"]) == ["V_DRONE_003"] and again["redone"] == {"V_DRONE_003": "the video file"}
    from synthaug.data.splits import VideoSplit

    split = VideoSplit(videos={"train": ["V_DRONE_001", "V_DRONE_003"], "val": ["V_DRONE_002"], "test": []})
    moved = _ingest(root, out, seed_counts=(), split=split, splits=("train", "val"))
    assert moved["redone"] == {"V_DRONE_002": "the split train -> val"}


def test_a_rerun_with_other_videos_does_not_report_the_old_seed_set_as_current(videos, tmp_path, caplog):
    out = tmp_path / "out"
    _ingest(videos / "a", out, seed_counts=(3, 6))
    caplog.set_level(logging.WARNING, logger="synthaug.ingest")
    # the same names, other films and labels: every shard is redone, none reported current
    other = _ingest(videos / "b", out, seed_counts=(3,))
    assert other["skipped_current"] == 0 and other["processed"] == 4
    assert set(other["redone"]) == {"V_DRONE_001", "V_DRONE_002", "V_DRONE_003"}
    assert all("the video file" in w for w in other["redone"].values())
    # drone_6 was drawn from the old videos and not redrawn: stale, with a warning, never current
    assert other["stale_seed_sets"] == [str(out / "seedsets/drone_6")]
    assert any("drone_6 was drawn by an earlier run" in m for m in _ingest_warnings(caplog))
    s3 = SeedSet.load(out / "seedsets/drone_3")
    src = {r["source_path"] for r in s3.records}
    assert src and all(p.startswith(str(videos / "b")) for p in src)
    # a folder with another video only: the seed set is drawn from it alone, not from the pool's older shards
    sub = tmp_path / "sub"
    for kind, ext in (("videos", "mp4"), ("labels", "json")):
        (sub / kind).mkdir(parents=True)
        shutil.copy2(videos / f"b/{kind}/V_DRONE_004.{ext}", sub / kind)
    only4 = _ingest(sub, out, seed_counts=(3,))
    assert only4["failed"] == {} and only4["skipped_current"] == 1  # the shard made from the same files
    assert {r["video"] for r in SeedSet.load(out / "seedsets/drone_3").records} == {"V_DRONE_004"}


def test_a_shard_of_an_older_synthaug_is_kept_until_its_files_change(videos, tmp_path):
    root = tmp_path / "a"
    shutil.copytree(videos / "a", root)
    out = tmp_path / "out"
    _ingest(root, out, seed_counts=())
    for k in (1, 2, 3):  # as written before the inputs were recorded
        head = out / f"pool/V_DRONE_00{k}/seedset.json"
        doc = json.loads(head.read_text())
        doc["ingest_fingerprint"] = ICFG.fingerprint()
        doc.pop("ingest_inputs"), doc.pop("ingest_options_fingerprint")
        head.write_text(json.dumps(doc))
    st = os.stat(root / "labels/V_DRONE_001.json")
    os.utime(root / "labels/V_DRONE_001.json", ns=(st.st_atime_ns, st.st_mtime_ns + 10**12))  # edited later
    again = _ingest(root, out, seed_counts=())
    assert list(again["videos"]) == ["V_DRONE_001"] and "V_DRONE_001.json newer" in again["redone"]["V_DRONE_001"]
    assert again["skipped_current"] == 2


def test_a_shard_keyed_by_an_older_form_of_fingerprint_says_so(videos, tmp_path, caplog):
    # shards recorded when a video's fingerprint was size + time stamp + head/tail hash: remade once, and the warning
    # says the fingerprint's form changed, not that the (byte-identical) video did
    root = tmp_path / "a"
    shutil.copytree(videos / "a", root)
    out = tmp_path / "out"
    _ingest(root, out, seed_counts=())
    head = out / "pool/V_DRONE_001/seedset.json"
    doc = json.loads(head.read_text())
    doc["ingest_inputs"]["video"] = {"size": doc["ingest_inputs"]["video"]["size"], "mtime_ns": 1, "head_sha256": "0"}
    doc["ingest_fingerprint"] = "old"
    head.write_text(json.dumps(doc))
    caplog.set_level(logging.WARNING, logger="synthaug.ingest")
    again = _ingest(root, out, seed_counts=())
    assert list(again["videos"]) == ["V_DRONE_001"] and again["skipped_current"] == 2
    why = again["redone"]["V_DRONE_001"]
    assert why == "the form of the video file's fingerprint (recorded by an older synthaug: head_sha256, mtime_ns, size)"
    assert any(f"V_DRONE_001: {why} changed since" in m for m in _ingest_warnings(caplog))
    # a video whose bytes changed is still named as such (same form, other values)
    shutil.copy2(videos / "b/videos/V_DRONE_003.mp4", root / "videos/V_DRONE_003.mp4")
    assert _ingest(root, out, seed_counts=())["redone"] == {"V_DRONE_003": "the video file"}
