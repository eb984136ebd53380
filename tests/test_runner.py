"""The protocol runner: (condition, seed) cells trained by `synthaug train`'s code, scored under the protocol,
cached and reused; the learning curve's files. Tiny generated videos with non-contiguous numbering."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from synthaug.detectors.training import TrainOptions
from synthaug.evaluate import runner as R
from synthaug.evaluate.cells import CellCache
from synthaug.evaluate.protocol import Protocol, example_protocol_dict

TRAIN = ["V_DRONE_003", "V_DRONE_010", "V_DRONE_027"]
VAL, TEST = ["V_DRONE_031"], ["V_DRONE_044", "V_DRONE_052"]
FAST = TrainOptions(scales=(1.0, 0.8), mining_rounds=1, mining_stride=4, val_stride=4, hog_components=2, box_calibration=0)


@pytest.fixture(scope="module")
def ws(tmp_path_factory):
    from synthaug.data.splits import VideoSplit, save_split
    from synthaug.data.synthvideo import make_panning_video

    root = tmp_path_factory.mktemp("runner")
    for i, stem in enumerate(TRAIN + VAL + TEST):
        make_panning_video(root, n_frames=12, size=(160, 128), seed=i, name=stem)
    make_panning_video(root, n_frames=12, size=(160, 128), seed=9, name="V_BIRD_002", class_name="bird")
    classes = {s: "drone" for s in TRAIN + VAL + TEST} | {"V_BIRD_002": "bird"}
    save_split(VideoSplit(videos={"train": TRAIN + ["V_BIRD_002"], "val": VAL, "test": TEST}, classes=classes,
                          info={"dataset": "runner test"}), root / "split.json")
    proto = Protocol.from_dict(example_protocol_dict(
        name="tiny", split_file=str(root / "split.json"), test={"split": "test", "frame_stride": 3},
        val={"split": "val", "frame_stride": 3}, min_training_seeds=2, scale_check=[0.75],
        bootstrap={"resamples": 50, "seed": 0, "ci": 0.95},
        patch={"negatives_per_positive": 3, "seed": 0, "patch_size": 40, "object_fraction": 0.7, "max_tries": 100}))
    paths = R.DataPaths(str(root / "videos"), str(root / "labels"), str(root / "split.json"), str(root / "work"))
    return {"root": root, "proto": proto, "paths": paths}


def make_runner(ws, **kw):
    kw.setdefault("options", FAST)
    kw.setdefault("scales", (1.0, 0.8))
    return R.ProtocolRunner(ws["proto"], "drone", ws["paths"], log=lambda m: None, **kw)


@pytest.fixture(scope="module")
def curve(ws):
    out = ws["root"] / "lc"
    res = R.learning_curve(make_runner(ws), detectors=["hog"], seed_counts=[6], all_frames=True, frame_step=4,
                           seeds=[0, 1], out=out)
    return {"out": out, "results": res}


def test_machine_info_records_the_dispatch_environment(monkeypatch):
    # an instruction set forced by environment (to reproduce another machine's cells, README) is part of the record
    for k in R.DISPATCH_ENV:
        monkeypatch.delenv(k, raising=False)
    assert R.machine_info()["dispatch_env"] == {}
    monkeypatch.setenv("ONEDNN_MAX_CPU_ISA", "AVX2")
    monkeypatch.setenv("SOMETHING_ELSE", "1")
    assert R.machine_info()["dispatch_env"] == {"ONEDNN_MAX_CPU_ISA": "AVX2"}


@pytest.mark.slow
def test_learning_curve_results_and_files(ws, curve):
    res = curve["results"]
    assert set(res) == {"hog", "hog x0.75"}
    for group in res.values():
        # every condition twice: boxes from the detector's box regression, and the windows' boxes (issue 15 item 5)
        assert set(group) == {"hog / 6 seeds", "hog / all training frames",
                              "hog / 6 seeds, window boxes", "hog / all training frames, window boxes"}
        for r in group.values():
            assert r.seed_ids == [0, 1] and r.stems == sorted(TEST)
            assert 0.0 <= r.mean_ap() <= 1.0
    assert res["hog"]["hog / 6 seeds"].patch_stems == sorted(TEST)  # patch protocol at scale 1 only
    assert res["hog x0.75"]["hog / 6 seeds"].patch_stems == []
    # the two rows score the same detections: the refined ones are those of the window boxes that
    # survive the second NMS (same scores, a subset), only the boxes (so the matches) differ
    from collections import Counter

    for name in ("hog / 6 seeds", "hog / all training frames"):
        a, b = res["hog"][name], res["hog"][f"{name}, window boxes"]
        for seed in (0, 1):
            for va, vb in zip(a.seeds[seed].videos, b.seeds[seed].videos):
                assert not Counter(va.scores.tolist()) - Counter(vb.scores.tolist())
    md = (curve["out"] / "learning_curve.md").read_text()
    assert "hog / 6 seeds" in md and "hog / all training frames" in md and "tiny" in md
    assert (curve["out"] / "learning_curve.png").stat().st_size > 1000
    assert json.loads((curve["out"] / "hog_6_seeds.json").read_text())["condition"] == "hog / 6 seeds"
    # seeds differ in what they trained on: the seed drives the seed draw of ingest
    meta = [sr.meta for sr in res["hog"]["hog / 6 seeds"].seeds.values()]
    assert all(m["positives"] == 6 for m in meta)
    # the plot's lines: the window-box rows are their own line, at the positives of the rows they re-score
    pts = R.curve_points(res)
    assert set(pts) == {"hog", "hog, window boxes", "hog x0.75", "hog x0.75, window boxes"}
    n_all = sum(sr.meta["positives"] for sr in res["hog"]["hog / all training frames"].seeds.values()) / 2
    for g in ("hog", "hog x0.75"):
        assert sorted(x for x, *_ in pts[g]["frame"]) == sorted(x for x, *_ in pts[f"{g}, window boxes"]["frame"])
        assert sorted(x for x, *_ in pts[g]["frame"]) == [6.0, n_all]
    at = {x: ap for x, ap, *_ in pts["hog, window boxes"]["frame"]}
    assert at[6.0] == pytest.approx(res["hog"]["hog / 6 seeds, window boxes"].mean_ap(0.5))
    assert at[n_all] == pytest.approx(res["hog"]["hog / all training frames, window boxes"].mean_ap(0.5))


def test_cells_are_reused_and_keyed_by_what_changes_a_result(ws, curve, monkeypatch):
    cache = CellCache(Path(ws["paths"].work_dir) / "cells")
    n_cells = len(cache)
    assert n_cells == 4  # 2 conditions x 2 seeds, each scored at both scales inside its cell

    def no_training(*a, **k):
        raise AssertionError("a cached cell was trained again")

    monkeypatch.setattr(R, "train_from_videos", no_training)
    again = R.learning_curve(make_runner(ws), detectors=["hog"], seed_counts=[6], all_frames=True, frame_step=4,
                             seeds=[0, 1])
    for group in ("hog", "hog x0.75"):
        for name, r in again[group].items():
            assert r.to_json() == curve["results"][group][name].to_json()
    # a read-only cache never trains; a changed budget, scale list or protocol is a new cell
    ro = make_runner(ws, cache=CellCache(cache.root, read_only=True),
                     options=dataclasses.replace(FAST, hog_components=3))
    assert ro.run(R.Condition("hog / 6 seeds", "hog", seed_count=6), seeds=[0]) == {}
    base = make_runner(ws)
    c = R.Condition("x", "hog", seed_count=6)
    ident = base.identity(c, 0)
    assert make_runner(ws, scales=(1.0,)).identity(c, 0) != ident
    assert make_runner(ws, options=dataclasses.replace(FAST, mining_rounds=2)).identity(c, 0) != ident
    other = Protocol.from_dict({**ws["proto"].to_dict(), "test": {"split": "test", "frame_stride": 2}})
    assert R.ProtocolRunner(other, "drone", ws["paths"], options=FAST, scales=(1.0, 0.8)).identity(c, 0) != ident
    assert base.identity(R.Condition("renamed", "hog", seed_count=6), 0) == ident  # the label is not the condition


@pytest.mark.slow
def test_cells_that_only_score_differently_read_the_trained_detector_back(ws, curve, monkeypatch):
    store = Path(ws["paths"].work_dir) / "cells" / "detectors"
    assert len(list(store.glob("*.pt"))) == 4 and len(CellCache(store)) == 4  # one per (condition, seed)
    real_train = R.train_from_videos
    calls = []

    def no_training(*a, **k):
        calls.append(1)
        return real_train(*a, **k)

    monkeypatch.setattr(R, "train_from_videos", no_training)
    c = R.Condition("hog / 6 seeds", "hog", seed_count=6)
    runner = make_runner(ws, scale_check=False, patches=False)  # a new cell (other scored scales, no patches)
    assert runner.identity(c, 1) != make_runner(ws).identity(c, 1)
    assert runner.training_identity(c, 1) == make_runner(ws).training_identity(c, 1)
    assert runner.training_identity(c, 1) != make_runner(ws, options=dataclasses.replace(FAST, mining_rounds=2)
                                                         ).training_identity(c, 1)
    res = runner.run(c, seeds=[1])[1.0]
    assert calls == []
    # the detector read back makes the very detections the trained one made in the learning curve's cell
    ref = curve["results"]["hog"]["hog / 6 seeds"]
    for va, vb in zip(res.seeds[1].videos, ref.seeds[1].videos):
        assert va.scores.tolist() == vb.scores.tolist() and va.tp.tolist() == vb.tp.tolist()
    cell = CellCache(Path(ws["paths"].work_dir) / "cells").get(runner.identity(c, 1))
    assert cell["detector_read_back"] is True
    # a damaged stored detector is trained again (once) and replaced
    ckpt = CellCache(store).path(runner.training_identity(c, 1)).with_suffix(".pt")
    ckpt.write_bytes(b"not a checkpoint")
    val = make_runner(ws, eval_split="val", patches=False, scale_check=False)
    val.run(c, seeds=[1])
    assert calls == [1]
    from synthaug.detectors.base import load_detector

    assert load_detector(ckpt).kind == "hog"


def test_detect_scales_score_another_pyramid_with_the_stored_detector(ws, curve, monkeypatch, capsys):
    """``detect_scales``: the scored detections use another pyramid than the training's; the cell is new, the
    trained detector is the stored one (no training), and the detections are those of the detector run directly
    with that pyramid."""
    from synthaug.detectors.base import load_detector
    from synthaug.evaluate.matching import match_videos
    from synthaug.evaluate.videos import detect_on_eval_set, refine_detections

    def no_training(*a, **k):
        raise AssertionError("a stored detector was trained again")

    monkeypatch.setattr(R, "train_from_videos", no_training)
    c = R.Condition("hog / 6 seeds", "hog", seed_count=6)
    plain = make_runner(ws, scale_check=False, patches=False)
    fine = make_runner(ws, scale_check=False, patches=False, detect_scales=(1.25, 1.0))
    assert fine.identity(c, 0) != plain.identity(c, 0)
    assert fine.identity(c, 0)["detect_scales"] == [1.25, 1.0] and "detect_scales" not in plain.identity(c, 0)
    assert fine.training_identity(c, 0) == plain.training_identity(c, 0)
    res = fine.run(c, seeds=[0])[1.0]
    det = load_detector(CellCache(Path(ws["paths"].work_dir) / "cells" / "detectors").path(
        plain.training_identity(c, 0)).with_suffix(".pt"))
    es, nms = fine.eval_set(1.0), ws["proto"].detection.nms_iou

    def direct(scales):
        raw = detect_on_eval_set(det, es, scales=scales, nms_iou=nms,
                                   max_detections=ws["proto"].detection.max_detections, refine_boxes=False)
        return match_videos(es.stems, refine_detections(det, es, raw, nms_iou=nms), es.boxes, ws["proto"])

    ref, train_pyramid = direct((1.25, 1.0)), direct((1.0, 0.8))
    assert [v.scores.tolist() for v in res.seeds[0].videos] == [v.scores.tolist() for v in ref]
    assert [v.tp.tolist() for v in res.seeds[0].videos] == [v.tp.tolist() for v in ref]
    assert [v.scores.tolist() for v in ref] != [v.scores.tolist() for v in train_pyramid]
    args = R.build_parser().parse_args(["learning-curve", "--detect-scales", "1.5", "1", "--out", "x"])
    assert args.detect_scales == [1.5, 1.0] and args.scales is None
    for bad in ("0", "-1", "nan"):
        with pytest.raises(SystemExit) as e:
            R.build_parser().parse_args(["learning-curve", "--detect-scales", "1", bad, "--out", "x"])
        assert e.value.code == 2 and "--detect-scales" in capsys.readouterr().err


def test_eval_split_val_scores_the_validation_videos_in_their_own_cells(ws, curve):
    c = R.Condition("hog / 6 seeds", "hog", seed_count=6)
    val = make_runner(ws, eval_split="val", patches=False, scale_check=False)
    assert val.test_videos() == VAL
    assert val.identity(c, 0) != make_runner(ws, patches=False, scale_check=False).identity(c, 0)
    res = val.run(c, seeds=[0])[1.0]
    assert res.split == "val" and res.stems == VAL
    with pytest.raises(ValueError, match="eval_split"):
        make_runner(ws, eval_split="train")


@pytest.mark.slow
def test_positive_videos_draw_the_positives_from_k_training_videos_and_mine_all(ws, curve):
    """``positive_videos`` (issue 15: more frames of the same videos vs more videos): the positives come from K
    training videos drawn by the seed, nested in K; mining and the box map keep every training video; the seed
    draw is ingested apart from the full set's; the key changes only when the option is set."""
    from synthaug.data.seedset import SeedSet
    from synthaug.data.video import read_labels
    from synthaug.detectors.video_training import TrainingInputError, positive_video_subset

    assert positive_video_subset(TRAIN, 3, 0) == sorted(TRAIN)
    for seed in range(4):
        one, two = positive_video_subset(TRAIN, 1, seed), positive_video_subset(TRAIN[::-1], 2, seed)
        assert set(one) < set(two) < set(TRAIN) and positive_video_subset(TRAIN, 2, seed) == two
    assert len({tuple(positive_video_subset(TRAIN, 1, s)) for s in range(8)}) > 1  # the seed draws the subset
    for bad in (0, 4):
        with pytest.raises(TrainingInputError, match="positive-videos"):
            positive_video_subset(TRAIN, bad, 0)

    runner = make_runner(ws, scale_check=False, patches=False)
    full_seedset = Path(ws["paths"].work_dir) / "ingest_drone_seed1" / "seedsets" / "drone_6" / "seedset.json"
    before = full_seedset.read_bytes()
    frames = R.Condition("f", "hog", seed_count=None, all_frames=True, frame_step=4, positive_videos=1)
    seeds = R.Condition("s", "hog", seed_count=4, positive_videos=2)
    assert "positive_videos" not in R.Condition("s", "hog", seed_count=4).identity()
    assert runner.identity(seeds, 1) != runner.identity(R.Condition("s", "hog", seed_count=4), 1)
    meta_f = runner.run(frames, seeds=[1])[1.0].seeds[1].meta
    chosen = positive_video_subset(TRAIN, 1, 1)
    labelled = [i for i, b in enumerate(read_labels(Path(ws["paths"].labels_dir) / f"{chosen[0]}.json").boxes)
                if b is not None]
    assert meta_f["positives"] == len(labelled[::4])
    res_s = runner.run(seeds, seeds=[1])[1.0]
    ss = SeedSet.load(Path(ws["paths"].work_dir) / "ingest_drone_seed1" / "positive_videos_2_seed1" / "seedsets" / "drone_4")
    assert len(ss) == 4 and {r["video"] for r in ss.records} <= set(positive_video_subset(TRAIN, 2, 1))
    assert res_s.seeds[1].meta["positives"] == 4
    assert full_seedset.read_bytes() == before  # the full set's seed draw is untouched
    store = CellCache(Path(ws["paths"].work_dir) / "cells" / "detectors")
    meta = store.get(runner.training_identity(frames, 1))["meta"]
    assert meta["positives"]["positive_videos"] == chosen and meta["split"]["train"] == sorted(TRAIN)
    args = R.build_parser().parse_args(["learning-curve", "--positive-videos", "14", "28", "--out", "x"])
    assert args.positive_videos == [14, 28]


@pytest.mark.slow
def test_synthetic_comparison_fits_each_training_seeds_own_seed_set_and_pairs_against_real(ws, curve):
    """Issue 16 under the protocol: + synthetic (a fit made on the fly per training seed) and + perturbed
    conditions share the real-only condition's seeds; each synthetic cell trains on its own seed set's fit."""
    from synthaug.data.seedset import SeedSet
    from synthaug.params import CaptureParams

    out = ws["root"] / "syn"
    fit_opts = {"budget": 40, "step_deg": 30.0, "sprite_size": 32, "init": "uniform"}
    res = R.synthetic_comparison(make_runner(ws), detectors=["hog"], seed_count=6,
                                 synthetic_ratios=[2], fit_distance="eucl", fit_options=fit_opts,
                                 perturb_copies=[2], copy_paste_ratios=[2], downscaled_copies=[1], faded_copies=[1],
                                 object_box=(None, "seed"), seeds=[0, 1], out=out)
    group = res["hog"]
    # HOG's synthetic positives: the realism critic's quarter by default (FAMILY_REALISM_KEEP)
    syn = "hog / 6 seeds + 2x synthetic (eucl, the 25% least synthetic of 4x drawn of each seed)"
    per = "hog / 6 seeds + 2x perturbed"
    framed = ("hog / 6 seeds + 2x synthetic (eucl, framed as the seeds (seed), the 25% least synthetic of 4x drawn of "
              "each seed)")
    cp, down = "hog / 6 seeds + 2x copy-paste (eucl silhouettes)", "hog / 6 seeds + 1x downscaled"
    faded = "hog / 6 seeds + 1x faded"
    assert list(group) == ["hog / 6 seeds", syn, framed, per, cp, down, faded]
    # the real-only cells are the learning curve's (same key): identical results, nothing retrained
    assert group["hog / 6 seeds"].to_json() == curve["results"]["hog"]["hog / 6 seeds"].to_json()
    fits = Path(ws["paths"].work_dir) / "fits"
    for seed in (0, 1):
        fit = fits / f"drone_6_seed{seed}_eucl.json"
        ss = SeedSet.load(Path(ws["paths"].work_dir) / f"ingest_drone_seed{seed}" / "seedsets" / "drone_6")
        theta, _, _ = CaptureParams.load_with_extra(fit)
        assert theta.batch_size == len(ss) == 6  # one row per seed of *this* training seed's seed set
        for name in (syn, per):
            assert group[name].seeds[seed].meta["positives"] == 6  # the real count; the added ones: the cell's metadata
    md = (out / "comparison.md").read_text()
    assert syn in md and per in md and "paired" in md.lower()
    # the cells record what was added, and the perturbed copies are the library's perturbation
    cache = CellCache(Path(ws["paths"].work_dir) / "cells")
    runner = make_runner(ws)
    cond_syn = R.Condition(syn, "hog", seed_count=6, synthetic_ratio=2.0, fit_distance="eucl",
                           fit_options=tuple(sorted(fit_opts.items())))
    cell = cache.get_or_compute(runner.identity(cond_syn, 1), lambda: pytest.fail("synthetic cell not cached"))
    assert cell["train"]["synthetic"]["count"] == 12 and cell["train"]["synthetic"]["params"].endswith("drone_6_seed1_eucl.json")
    assert cell["train"]["synthetic"]["realism_keep"] == 0.25 and cond_syn.identity()["realism_keep"] == 0.25
    assert cell["train"]["synthetic"]["realism_selection"] == cond_syn.identity()["realism_selection"] == "seed"
    assert "object_box" not in cell["train"]["synthetic"] and "object_box" not in cond_syn.identity()
    # the framed condition: its own key (the framing), the same fit, the framing reaching the generator
    cond_framed = dataclasses.replace(cond_syn, name=framed, object_box="seed")
    assert cond_framed.identity()["object_box"] == "seed"
    cell = cache.get_or_compute(runner.identity(cond_framed, 1), lambda: pytest.fail("framed cell not cached"))
    assert cell["train"]["synthetic"]["object_box"] == "seed" and cell["train"]["synthetic"]["count"] == 12
    cond_per = R.Condition(per, "hog", seed_count=6, perturb_copies=2)
    cell = cache.get_or_compute(runner.identity(cond_per, 0), lambda: pytest.fail("perturbed cell not cached"))
    assert cell["train"]["perturbed"] == {"copies": 2, "count": 12}
    # where the cell was computed (not part of the key): the instruction set torch ran and its threads
    import torch

    assert cell["machine"]["cpu_capability"] == torch.backends.cpu.get_cpu_capability()
    assert cell["machine"]["torch"] == torch.__version__ and cell["machine"]["torch_threads"] >= 1
    # the machine that trained the stored detector, and both in the results' per-seed metadata (its files)
    assert cell["train"]["machine"] == R.machine_info()
    seed_meta = R.ProtocolResult.from_json(cell["scales"]["1.0"]).seeds[0].meta
    assert seed_meta["trained_on"] == cell["train"]["machine"] and seed_meta["scored_on"] == cell["machine"]
    cond_cp = R.Condition(cp, "hog", seed_count=6, fit_distance="eucl", fit_options=tuple(sorted(fit_opts.items())),
                          copy_paste_ratio=2.0)
    cell = cache.get_or_compute(runner.identity(cond_cp, 1), lambda: pytest.fail("copy-paste cell not cached"))
    assert cell["train"]["synthetic"]["copy_paste"] == {"ratio": 2.0, "count": 12}
    assert cell["train"]["synthetic"]["count"] == 0 and cell["train"]["synthetic"]["params"].endswith("drone_6_seed1_eucl.json")
    assert "copy_paste_ratio" not in R.Condition("r", "hog", seed_count=6).identity()
    # a given fit file is part of the key by its bytes; the new fields leave older keys unchanged
    given = R.Condition("g", "hog", seed_count=6, params=str(fits / "drone_6_seed{seed}_eucl.json"), synthetic_ratio=2.0)
    k0 = runner.identity(given, 0)["condition"]["params_sha256"]
    assert k0 and k0 != runner.identity(given, 1)["condition"]["params_sha256"]
    assert "perturb_copies" not in R.Condition("r", "hog", seed_count=6).identity()
    # downscaled copies: their own cell, keyed by the count; they reach the training (its metadata)
    cond_down = R.Condition(down, "hog", seed_count=6, downscaled_copies=1)
    assert "downscaled_copies" not in R.Condition("r", "hog", seed_count=6).identity()
    assert cond_down.identity()["downscaled_copies"] == 1
    cell = cache.get_or_compute(runner.identity(cond_down, 0), lambda: pytest.fail("downscaled cell not cached"))
    assert cell["train"]["downscaled"]["copies"] == 1 and cell["train"]["downscaled"]["count"] >= 1
    # faded copies likewise: keyed by the count, absent from older keys, one copy of each of the 6 seeds
    cond_faded = R.Condition(faded, "hog", seed_count=6, faded_copies=1)
    assert "faded_copies" not in R.Condition("r", "hog", seed_count=6).identity()
    assert cond_faded.identity()["faded_copies"] == 1
    cell = cache.get_or_compute(runner.identity(cond_faded, 1), lambda: pytest.fail("faded cell not cached"))
    assert cell["train"]["faded"]["copies"] == 1 and cell["train"]["faded"]["count"] == 6


def test_runner_fits_one_file_per_mesh_and_refuses_a_stored_fit_of_another_mesh(ws, tmp_path):
    """A cell with ``mesh`` reads and writes ``..._<distance>_<mesh stem>.json``: a fit made for another shape (the
    default quadcopter's, at the path without a mesh) is never rendered with this mesh; a stored file whose
    recorded mesh differs from the cell's is refused with a clear error instead of being used."""
    import torch

    from synthaug.params import CaptureParams

    runner = R.ProtocolRunner(ws["proto"], "drone", dataclasses.replace(ws["paths"], work_dir=str(tmp_path)),
                              log=lambda m: None, options=FAST, scales=(1.0, 0.8))
    fits = tmp_path / "fits"
    fits.mkdir()
    theta = CaptureParams.sample(6, generator=torch.Generator().manual_seed(0))
    theta.save(fits / "drone_6_seed0_eucl.json", metadata={"mesh": "quadcopter"})
    glb = tmp_path / "twin_prop_airplane.glb"
    theta.save(fits / "drone_6_seed0_eucl_twin_prop_airplane.json", metadata={"mesh": str(glb)})
    plain = R.Condition("s", "hog", seed_count=6, synthetic_ratio=2.0, fit_distance="eucl")
    assert runner.params_for(plain, 0)(tmp_path) == fits / "drone_6_seed0_eucl.json"
    meshed = dataclasses.replace(plain, mesh=str(glb))
    assert runner.params_for(meshed, 0)(tmp_path) == fits / "drone_6_seed0_eucl_twin_prop_airplane.json"
    # the same stem, another shape: the recorded mesh decides
    other = dataclasses.replace(plain, mesh=str(tmp_path / "elsewhere" / "twin_prop_airplane.glb"))
    with pytest.raises(ValueError, match="fitted with mesh"):
        runner.params_for(other, 0)(tmp_path)
    # a fit without a recorded mesh (older files) is read as before
    theta.save(fits / "drone_6_seed1_eucl.json")
    assert runner.params_for(plain, 1)(tmp_path) == fits / "drone_6_seed1_eucl.json"


def test_cells_of_one_seed_set_make_its_fit_once(ws, tmp_path, monkeypatch):
    """Two cells needing the same missing fit at once (two runner processes; here two threads, each with its own
    lock file handle): one makes it, the other waits and reads it, and neither fails (stop 101: two processes
    fitting into one file had crashed one of them)."""
    import threading
    import time

    import torch

    import synthaug.fit.fitting as fitting
    from synthaug.params import CaptureParams

    made = []

    def slow_fit(seedset, mesh, out, cfg):
        made.append(out)
        time.sleep(0.5)
        CaptureParams.sample(6, generator=torch.Generator().manual_seed(0)).save(out, metadata={"mesh": mesh})
        return out

    monkeypatch.setattr(fitting, "fit_seedset", slow_fit)
    runner = R.ProtocolRunner(ws["proto"], "drone", dataclasses.replace(ws["paths"], work_dir=str(tmp_path)),
                              log=lambda m: None, options=FAST, scales=(1.0, 0.8))
    cond = R.Condition("s", "hog", seed_count=6, synthetic_ratio=2.0, fit_distance="eucl")
    got = []
    threads = [threading.Thread(target=lambda: got.append(runner.params_for(cond, 0)(tmp_path))) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert got == [tmp_path / "fits" / "drone_6_seed0_eucl.json"] * 2 and made == got[:1]


def test_runner_scales_option_parses_and_refuses_a_non_positive_factor(capsys):
    """``--scales`` (the pyramid of mining, validation and scoring; part of a cell's key) for both subcommands."""
    args = R.build_parser().parse_args(["learning-curve", "--scales", "1.25", "0.33", "--out", "x"])
    assert args.scales == [1.25, 0.33]
    assert R.build_parser().parse_args(["synthetic", "--out", "x"]).scales is None
    for bad in ("0", "-0.5", "nan"):
        with pytest.raises(SystemExit) as e:
            R.build_parser().parse_args(["synthetic", "--scales", "1", bad, "--out", "x"])
        assert e.value.code == 2
        assert "--scales" in capsys.readouterr().err


def test_runner_downscaled_copies_option_parses_and_refuses_zero(capsys):
    args = R.build_parser().parse_args(["synthetic", "--downscaled-copies", "1", "3", "--out", "x"])
    assert args.downscaled_copies == [1, 3]
    assert R.build_parser().parse_args(["synthetic", "--out", "x"]).downscaled_copies == []
    with pytest.raises(SystemExit) as e:
        R.build_parser().parse_args(["synthetic", "--downscaled-copies", "0", "--out", "x"])
    assert e.value.code == 2 and "--downscaled-copies" in capsys.readouterr().err
    assert R.build_parser().parse_args(["synthetic", "--faded-copies", "2", "--out", "x"]).faded_copies == [2]
    assert R.build_parser().parse_args(["synthetic", "--out", "x"]).object_box == ["none"]
    assert R.build_parser().parse_args(["synthetic", "--object-box", "none", "seed", "--out", "x"]).object_box == [
        "none", "seed"]
    assert R.build_parser().parse_args(["synthetic", "--out", "x"]).shape_variation == ["default"]
    # --mining-frame-scale: a training option (TrainOptions), refused at parse time when not 0 < LOW <= HIGH
    args = R.build_parser().parse_args(["learning-curve", "--mining-frame-scale", "0.75", "2", "--out", "x"])
    assert R.train_options(args).mining_frame_scale == (0.75, 2.0)
    assert R.train_options(R.build_parser().parse_args(["learning-curve", "--out", "x"])).mining_frame_scale == (1.0, 1.0)
    for bad in (["2", "1"], ["0", "1"]):
        with pytest.raises(SystemExit) as e:
            R.main(["learning-curve", "--mining-frame-scale", *bad, "--out", "x"])
        assert e.value.code == 2 and "--mining-frame-scale" in capsys.readouterr().err
    # --ada-energy-floor: AdaBoost's training option, a number >= 0 (1, the default, is part of AdaBoost's keys)
    assert R.train_options(R.build_parser().parse_args(["learning-curve", "--ada-energy-floor", "0", "--out", "x"])
                           ).ada_energy_floor == 0.0
    with pytest.raises(SystemExit) as e:
        R.build_parser().parse_args(["learning-curve", "--ada-energy-floor", "-1", "--out", "x"])
    assert e.value.code == 2 and "--ada-energy-floor" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        R.build_parser().parse_args(["synthetic", "--shape-variation", "-0.2", "--out", "x"])
    assert e.value.code == 2 and "--shape-variation" in capsys.readouterr().err
    assert R.build_parser().parse_args(["synthetic", "--shape-variation", "0", "0.3", "--out", "x"]).shape_variation == [
        0.0, 0.3]
    # a varied-shape condition has its own key; at 0 the key is the one cells had before the option existed
    plain = R.Condition("c", "cnn", seed_count=100, synthetic_ratio=20.0)
    assert "shape_variation" not in plain.identity()
    assert dataclasses.replace(plain, shape_variation=0.3).identity()["shape_variation"] == 0.3
    with pytest.raises(SystemExit) as e:
        R.build_parser().parse_args(["synthetic", "--faded-copies", "0", "--out", "x"])
    assert e.value.code == 2 and "--faded-copies" in capsys.readouterr().err
    # --faded-contrast: a range (negative: inverted copies), part of the condition's key only when given
    args = R.build_parser().parse_args(["synthetic", "--faded-copies", "1", "--faded-contrast", "-1", "-0.5", "--out", "x"])
    assert args.faded_contrast == [-1.0, -0.5]
    assert R.build_parser().parse_args(["synthetic", "--out", "x"]).faded_contrast is None
    assert "faded_contrast" not in R.Condition("f", "hog", seed_count=6, faded_copies=1).identity()
    inv = R.Condition("i", "hog", seed_count=6, faded_copies=1, faded_contrast=(-1.0, -0.5))
    assert inv.identity()["faded_contrast"] == (-1.0, -0.5)
    assert inv.identity() != R.Condition("f", "hog", seed_count=6, faded_copies=1).identity()


def test_later_options_leave_old_cell_keys_unchanged_at_their_former_values(capsys):
    """``--mining-select`` / ``--mining-patience`` / ``--box-model`` (TrainOptions fields added after cells were
    cached): at ``fp`` / 0 / ``ridge`` a cell's key is the one before them; any other value is a new cell, and the
    default box model (``ensemble``) is one: cells of the default options were trained again."""
    from synthaug.evaluate.cells import cell_key

    proto = Protocol.from_dict(example_protocol_dict(name="tiny", split_file="split.json"))
    paths = R.DataPaths("videos", "labels", "split.json", "work")
    c = R.Condition("cnn / 12 seeds", "cnn", seed_count=12)

    def ident(**kw):
        return R.ProtocolRunner(proto, "drone", paths, options=TrainOptions(**kw), log=lambda m: None).identity(c, 1)

    base = ident(box_model="ridge", box_calibration=0)  # (the box calibration, stop 73: the CNN's default is on)
    later = ("mining_select", "mining_patience", "box_model", "hog_kmeans_restarts", "cnn_finetune_epochs",
             "mining_frame_scale", "ada_energy_floor", "ada_transfer", "ada_cascade", "box_calibration",
             "box_calibration_form")
    assert base["options"] == {k: v for k, v in dataclasses.asdict(TrainOptions(ada_rounds=100)).items() if k not in later}
    assert ident(mining_select="fp", mining_patience=0, box_model="ridge", box_calibration=0) == base
    assert ident(box_model="ridge")["options"]["box_calibration"]["stride"] == 20  # scored differently: a new cell
    if R.TRAINING_VERSION == 6:  # the key computed before the three options existed (same protocol, paths, condition)
        assert cell_key(base) == "6475b1e4fead8163625ca26e"
    assert ident()["options"]["box_model"] == "ensemble" and cell_key(ident()) != cell_key(base)
    keys = {cell_key(base), cell_key(ident(box_model="ridge", box_calibration=0, mining_select="ap")),
            cell_key(ident(box_model="ridge", box_calibration=0, mining_patience=1)),
            cell_key(ident(box_model="ridge", box_calibration=0, mining_select="ap", mining_patience=1)),
            cell_key(ident())}
    assert len(keys) == 5
    # the command line reaches them; a negative patience is a usage error naming the option
    args = R.build_parser().parse_args(["synthetic", "--mining-select", "ap", "--mining-patience", "1", "--out", "x"])
    assert (args.mining_select, args.mining_patience) == ("ap", 1)
    args = R.build_parser().parse_args(["learning-curve", "--out", "x"])
    assert (args.mining_select, args.mining_patience, args.box_model) == (None, None, "ensemble")  # the family's
    assert R.build_parser().parse_args(["learning-curve", "--box-model", "ridge", "--out", "x"]).box_model == "ridge"
    for bad in (["--mining-patience", "-1"], ["--mining-select", "recall"], ["--box-model", "svm"]):
        with pytest.raises(SystemExit) as e:
            R.build_parser().parse_args(["synthetic", *bad, "--out", "x"])
        assert e.value.code == 2 and bad[0] in capsys.readouterr().err


def test_runner_budget_options_reach_the_cell_key(capsys):
    """``--ada-rounds`` / ``--ada-candidates`` / ... (the families' budgets, one spelling with ``synthaug train``)
    reach the runner's TrainOptions and so the cell key; the defaults are TrainOptions' own; a budget below its
    floor is a usage error naming the flag."""
    from synthaug.evaluate.cells import cell_key

    default = R.train_options(R.build_parser().parse_args(["learning-curve", "--out", "x"]))
    assert default == TrainOptions()
    args = R.build_parser().parse_args(["synthetic", "--ada-rounds", "300", "--ada-candidates", "4000",
                                        "--cnn-epochs", "5", "--mining-rounds", "2", "--mining-stride", "10",
                                        "--cnn-finetune-epochs", "3", "--out", "x"])
    opts = R.train_options(args)
    assert (opts.ada_rounds, opts.ada_candidates, opts.cnn_epochs, opts.mining_rounds, opts.mining_stride,
            opts.cnn_finetune_epochs) == (300, 4000, 5, 2, 10, 3)
    assert dataclasses.replace(opts, ada_rounds=None, ada_candidates=2000, cnn_epochs=12, mining_rounds=3,
                               mining_stride=30, cnn_finetune_epochs=4) == default
    proto = Protocol.from_dict(example_protocol_dict(name="tiny", split_file="split.json"))
    paths = R.DataPaths("videos", "labels", "split.json", "work")
    c = R.Condition("adaboost / 12 seeds", "adaboost", seed_count=12)

    def key(o):
        return cell_key(R.ProtocolRunner(proto, "drone", paths, options=o, log=lambda m: None).identity(c, 0))

    assert key(dataclasses.replace(default, ada_rounds=100)) != key(default)
    # AdaBoost's family defaults (300 rounds, mining by validation AP with one round of patience) written out or
    # left at None are one cell; HOG's key does not see AdaBoost's defaults
    assert key(dataclasses.replace(default, ada_rounds=300, mining_select="ap", mining_patience=1)) == key(default)
    assert key(dataclasses.replace(default, mining_patience=0)) != key(default)
    hog = R.Condition("hog / 12 seeds", "hog", seed_count=12)
    ident = R.ProtocolRunner(proto, "drone", paths, options=default, log=lambda m: None).identity(hog, 0)
    assert ident == R.ProtocolRunner(proto, "drone", paths, options=TrainOptions(ada_rounds=100, mining_select="fp",
                                                                                   mining_patience=0),
                                     log=lambda m: None).identity(hog, 0)
    assert key(dataclasses.replace(default, ada_candidates=4000)) != key(default)
    assert key(dataclasses.replace(default, mining_stride=10)) != key(default)
    cnn = R.Condition("cnn / 12 seeds", "cnn", seed_count=12)

    def cnn_key(o):
        return cell_key(R.ProtocolRunner(proto, "drone", paths, options=o, log=lambda m: None).identity(cnn, 0))

    # the CNN's fine-tuning is in the CNN's key only, and only where positives are added (real only: nothing to
    # fine-tune after, the same training)
    assert cnn_key(dataclasses.replace(default, cnn_finetune_epochs=3)) == cnn_key(default)
    cnn = R.Condition("cnn / 12 seeds + 20x synthetic", "cnn", seed_count=12, params="p.json", synthetic_ratio=20)
    assert cnn_key(dataclasses.replace(default, cnn_finetune_epochs=3)) != cnn_key(default)
    cnn = R.Condition("cnn / 12 seeds + perturbed", "cnn", seed_count=12, perturb_copies=2)
    assert cnn_key(dataclasses.replace(default, cnn_finetune_epochs=3)) != cnn_key(default)
    assert key(dataclasses.replace(default, cnn_finetune_epochs=3)) == key(default)
    # AdaBoost's transfer rule: in AdaBoost's keys only where positives are added (real only: the same training);
    # the flag reaches the options
    ada = R.Condition("adaboost / 12 seeds", "adaboost", seed_count=12)

    def ada_key(o, c):
        return cell_key(R.ProtocolRunner(proto, "drone", paths, options=o, log=lambda m: None).identity(c, 0))

    on = dataclasses.replace(default, ada_transfer=True)
    assert ada_key(on, ada) == ada_key(default, ada)
    ada_syn = R.Condition("adaboost / 12 seeds + 20x synthetic", "adaboost", seed_count=12, params="p.json",
                          synthetic_ratio=20)
    assert ada_key(on, ada_syn) != ada_key(default, ada_syn)
    assert cnn_key(on) == cnn_key(default)
    assert R.train_options(R.build_parser().parse_args(["synthetic", "--ada-transfer", "--out", "x"])).ada_transfer
    assert not R.train_options(R.build_parser().parse_args(["synthetic", "--out", "x"])).ada_transfer
    # AdaBoost's real-positive cascade (the default): the same (added positives only; the flag reaches the options)
    old = dataclasses.replace(default, ada_cascade="all")
    assert ada_key(old, ada) == ada_key(default, ada) and ada_key(old, ada_syn) != ada_key(default, ada_syn)
    assert R.train_options(R.build_parser().parse_args(["synthetic", "--ada-cascade", "real", "--out", "x"])
                           ).ada_cascade == "real"
    assert R.train_options(R.build_parser().parse_args(["synthetic", "--ada-cascade", "all", "--out", "x"])
                           ).ada_cascade == "all"
    assert R.train_options(R.build_parser().parse_args(["synthetic", "--out", "x"])).ada_cascade == "real"  # default
    for bad in (["--ada-rounds", "0"], ["--ada-candidates", "-3"], ["--mining-stride", "0"], ["--cnn-finetune-epochs", "-1"]):
        with pytest.raises(SystemExit) as e:
            R.build_parser().parse_args(["learning-curve", *bad, "--out", "x"])
        assert e.value.code == 2 and bad[0] in capsys.readouterr().err


PAPER_DRAWS = dict(pose_sampling=("uniform",), shape_variation=(0.0,), quantize=(False,), distractor_ratio=0.0)
"""``synthetic_comparison``'s options for the paper's way of drawing synthetic positives, whatever the family's."""


def _record_in_table_order(made):
    """A stand-in for ``R._run_into`` that lists the conditions in ``made`` as the tables do: each kind's real only
    first, although ``synthetic_comparison`` runs it after the added ones (the test below checks both orders)."""
    pending = {}  # each kind's added conditions, listed once its real only (run last) comes

    def run_into(results, runner, c, seeds):
        if c.name == f"{c.kind} / {c.seed_count} seeds":
            made.extend([c, *pending.pop(c.kind, [])])
        else:
            pending.setdefault(c.kind, []).append(c)
    return run_into


def test_synthetic_comparison_trains_real_only_last_and_lists_it_first(monkeypatch):
    """Each detector's real-only condition runs after its added ones (a second process training those cells is
    waited for at the end, not ahead of every added cell), and stays the first row of its groups (every scale)."""
    made = []

    def run_into(results, runner, c, seeds):
        made.append(c.name)
        for group in (c.kind, f"{c.kind} x2"):
            results.setdefault(group, {})[c.name] = c

    monkeypatch.setattr(R, "_run_into", run_into)
    res = R.synthetic_comparison(None, detectors=["adaboost", "hog"], seed_count=12, synthetic_ratios=[20],
                                 params="f{seed}.json", perturb_copies=[2], realism_keep=(1.0,), **PAPER_DRAWS)
    ada = ["adaboost / 12 seeds + 20x synthetic (f{seed}, share 0.25)",
           "adaboost / 12 seeds + 2x perturbed, share 0.25"]
    hog = ["hog / 12 seeds + 20x synthetic (f{seed})", "hog / 12 seeds + 2x perturbed"]
    assert made == [*ada, "adaboost / 12 seeds", *hog, "hog / 12 seeds"]
    for kind, added in (("adaboost", ada), ("hog", hog)):
        for group in (kind, f"{kind} x2"):
            assert list(res[group]) == [f"{kind} / 12 seeds", *added]
            assert res[group][f"{kind} / 12 seeds"].synthetic_ratio == 0 and not res[group][added[0]].perturb_copies


def test_synthetic_comparison_makes_one_condition_per_capture_sampling_and_effect_left_out(monkeypatch, capsys):
    """The paper's Figs. 10 and 9 under the protocol: ``--capture-sampling`` and ``--effects-off`` each add a
    synthetic condition per value, with keys of their own; at their defaults the keys are the ones cells had."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["hog"], seed_count=100, synthetic_ratios=[20], params="f{seed}.json",
                           capture_sampling=("seed", "uniform"), effects_off=(None, "motion_blur"),
                           realism_keep=(1.0,))  # every draw: the names and keys the cells had
    syn = [c for c in made if c.synthetic_ratio]
    assert [(c.capture_sampling, c.effects_off) for c in syn] == [
        ("seed", ()), ("seed", ("motion_blur",)), ("uniform", ()), ("uniform", ("motion_blur",))]
    made.clear()  # several effects left out in one condition
    R.synthetic_comparison(None, detectors=["hog"], seed_count=100, synthetic_ratios=[20], params="f{seed}.json",
                           effects_off=(("boundary_blur", "motion_blur"),), realism_keep=(1.0,))
    both = [c for c in made if c.synthetic_ratio]
    assert [c.effects_off for c in both] == [("boundary_blur", "motion_blur")]
    assert both[0].name == "hog / 100 seeds + 20x synthetic (f{seed}, without boundary_blur and motion_blur)"
    # the family's default (None): resolved into the key, so a CNN's default cell is the cell that names its blurs
    # left out, and the CNN with every effect ((), "none") keeps the key its cells had before the default
    made.clear()
    R.synthetic_comparison(None, detectors=["cnn", "hog"], seed_count=100, synthetic_ratios=[20],
                           params="f{seed}.json", effects_off=(None, (), ("boundary_blur", "motion_blur")),
                           background_sampling=("seed",),  # the CNN's former cells: their own seeds' backgrounds
                           realism_keep=(1.0,))
    fam = [c for c in made if c.synthetic_ratio]
    blurs = ("boundary_blur", "motion_blur")
    assert [(c.kind, c.effects_off) for c in fam] == [("cnn", blurs), ("cnn", ()), ("hog", ()), ("hog", blurs)]
    cnn_default = R.Condition("x", "cnn", seed_count=100, params="f{seed}.json", synthetic_ratio=20.0,
                              background_sampling="seed")
    assert cnn_default.identity() == fam[0].identity() and cnn_default.effects_off == ("boundary_blur", "motion_blur")
    assert "effects_off" not in fam[1].identity() and "effects_off" not in R.Condition("x", "cnn").identity()
    assert fam[1].name == "cnn / 100 seeds + 20x synthetic (f{seed})"
    none = R.build_parser().parse_args(["synthetic", "--effects-off", "none", "default", "--out", "x"])
    assert none.effects_off == ["none", "default"]
    assert [c.name for c in syn][1:3] == ["hog / 100 seeds + 20x synthetic (f{seed}, without motion_blur)",
                                          "hog / 100 seeds + 20x synthetic (f{seed}, capture uniform)"]
    keys = [c.identity() for c in syn]
    assert "capture_sampling" not in keys[0] and "effects_off" not in keys[0]  # the paper's: the former key
    assert keys[0] == R.Condition("x", "hog", seed_count=100, params="f{seed}.json", synthetic_ratio=20.0,
                                  realism_keep=1.0).identity()
    assert keys[1]["effects_off"] == ("motion_blur",) and keys[2]["capture_sampling"] == "uniform"
    assert len({json.dumps(k, sort_keys=True) for k in keys}) == 4
    # the command line: one condition per value; effect names checked when parsed
    args = R.build_parser().parse_args(["synthetic", "--capture-sampling", "seed", "uniform", "--effects-off", "none",
                                        "object_noise", "--out", "x"])
    assert args.capture_sampling == ["seed", "uniform"] and args.effects_off == ["none", "object_noise"]
    plain = R.build_parser().parse_args(["synthetic", "--out", "x"])
    assert plain.capture_sampling == ["seed"] and plain.effects_off == ["default"]
    assert R.build_parser().parse_args(["synthetic", "--out", "x"]).effects_off == ["default"]
    joined = R.build_parser().parse_args(["synthetic", "--effects-off", "motion_blur+boundary_blur", "--out", "x"])
    assert joined.effects_off == ["boundary_blur+motion_blur"]  # one spelling whatever the order
    for bad in (["--effects-off", "speckle"], ["--capture-sampling", "fitted"], ["--effects-off", "motion_blur+speckle"],
                ["--effects-off", "motion_blur+motion_blur"]):
        with pytest.raises(SystemExit) as e:
            R.build_parser().parse_args(["synthetic", *bad, "--out", "x"])
        assert e.value.code == 2 and bad[0] in capsys.readouterr().err


def test_synthetic_share_default_is_the_familys_and_keeps_the_cells_keys(monkeypatch, capsys):
    """``--synthetic-share`` unset: each family's own share, resolved into the condition. AdaBoost's (0.25) cell is
    the cell of ``--synthetic-share 0.25`` (same key and name), ``count`` keeps the key AdaBoost's cells by count had
    before the default (no share in it); HOG's default is by count (its former key); a real-only cell has no share."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    for share in (None, 0.25, "count"):
        R.synthetic_comparison(None, detectors=["adaboost", "hog"], seed_count=12, synthetic_ratios=[20],
                               params="f{seed}.json", perturb_copies=[5], synthetic_share=share,
                               realism_keep=(1.0,), **PAPER_DRAWS)  # the paper's draws: the names the cells had
    default, explicit, count = (made[i * 6:(i + 1) * 6] for i in range(3))
    assert [(c.kind, c.synthetic_share) for c in default] == [
        ("adaboost", None), ("adaboost", 0.25), ("adaboost", 0.25), ("hog", None), ("hog", None), ("hog", None)]
    assert [c.identity() for c in default] == [c.identity() for c in explicit[:3]] + [c.identity() for c in count[3:]]
    assert [c.name for c in default[:3]] == [c.name for c in explicit[:3]]
    assert default[1].name == "adaboost / 12 seeds + 20x synthetic (f{seed}, share 0.25)"
    assert default[2].name == "adaboost / 12 seeds + 5x perturbed, share 0.25"
    assert explicit[4].identity()["synthetic_share"] == 0.25 and explicit[4].name.endswith("share 0.25)")
    before = R.Condition("x", "adaboost", seed_count=12, params="f{seed}.json", synthetic_ratio=20.0,
                         synthetic_share="count", realism_keep=1.0, pose_sampling="uniform", shape_variation=0.0,
                         quantize=False, distractor_ratio=0.0)
    assert count[1].identity() == before.identity() and "synthetic_share" not in before.identity()
    assert count[1].name == "adaboost / 12 seeds + 20x synthetic (f{seed})"
    assert R.Condition("x", "adaboost", synthetic_share=0.25).synthetic_share is None  # nothing added: no share
    # the command line: a number or "count"; anything else is a usage error naming the option
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).synthetic_share is None
    assert parse(["synthetic", "--synthetic-share", "count", "--out", "x"]).synthetic_share == "count"
    assert parse(["synthetic", "--synthetic-share", "0.1", "--out", "x"]).synthetic_share == 0.1
    with pytest.raises(SystemExit) as e:
        parse(["synthetic", "--synthetic-share", "half", "--out", "x"])
    assert e.value.code == 2 and "--synthetic-share" in capsys.readouterr().err
    with pytest.raises(ValueError, match="synthetic_share"):
        R.Condition("x", "adaboost", synthetic_ratio=20.0, synthetic_share="half")


def _refused(parse, argv, option, capsys):
    """``parse(argv)`` exits with argparse's usage error (2), its message naming ``option``."""
    with pytest.raises(SystemExit) as e:
        parse(argv)
    assert e.value.code == 2 and option in capsys.readouterr().err


def _added_positives(ws, monkeypatch, *conditions):
    """The ``AddedPositives`` each condition's training gets from the runner (seed 0; stopped before any training)."""
    seen = []

    def fake_train(*args, added, **kwargs):
        seen.append(added)
        raise RuntimeError("stopped before training")

    monkeypatch.setattr(R, "train_from_videos", fake_train)
    for c in conditions:
        with pytest.raises(RuntimeError, match="stopped before training"):
            make_runner(ws)._train(c, 0)
    return seen


def test_quantize_is_a_condition_of_its_own_and_keeps_the_former_keys(ws, monkeypatch):
    """``--quantize on`` adds an 8-bit condition per synthetic ratio (named so, with ``quantize`` in its key and in the
    ``AddedPositives`` its training gets); off, the default, keeps every former key and name."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["adaboost"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           realism_keep=(1.0,), **{**PAPER_DRAWS, "quantize": (False, True, True, "native_scale")})
    real, plain, eight, native = made
    assert "quantize" not in plain.identity() and eight.identity()["quantize"] is True
    assert {k: v for k, v in eight.identity().items() if k != "quantize"} == plain.identity()
    assert native.identity() == {**eight.identity(), "quantize": "native_scale"}
    assert plain.name == "adaboost / 12 seeds + 20x synthetic (f{seed}, share 0.25)"
    assert eight.name == "adaboost / 12 seeds + 20x synthetic (f{seed}, share 0.25, 8-bit)"
    assert native.name == "adaboost / 12 seeds + 20x synthetic (f{seed}, share 0.25, 8-bit at native scale)"
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).quantize == ["default"]
    assert parse(["synthetic", "--quantize", "off", "on", "--out", "x"]).quantize == ["off", "on"]
    with pytest.raises(SystemExit):
        parse(["synthetic", "--quantize", "sometimes", "--out", "x"])
    # the cell's training gets it: AddedPositives.quantize as the condition says (stopped before any training)
    assert [a.quantize for a in _added_positives(ws, monkeypatch, plain, eight, native)] == [False, True,
                                                                                              "native_scale"]
    # the command line's word reaches the comparison as the value
    seen = []
    monkeypatch.setattr(R, "synthetic_comparison", lambda *a, **k: seen.append(k["quantize"]) or {})
    R.main(["synthetic", "--quantize", "default", "off", "on", "native_scale", "--out", str(ws["root"] / "q")])
    assert seen == [(None, False, True, "native_scale")]


def test_distractors_join_every_synthetic_condition_and_keep_the_former_keys(ws, monkeypatch, capsys):
    """``--distractor-ratio K``: every synthetic condition (not real only, not the perturbed baseline) adds K rendered
    distractors per seed, named so, ``distractor_ratio`` in its key and its training's ``AddedPositives``; 0, the
    default, keeps every former key and name; a condition without synthetic positives and a negative ratio are
    refused."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["adaboost"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           perturb_copies=[5], realism_keep=(1.0,), **PAPER_DRAWS)
    real, plain, perturbed = made
    made.clear()
    R.synthetic_comparison(None, detectors=["adaboost"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           perturb_copies=[5], realism_keep=(1.0,), **{**PAPER_DRAWS, "distractor_ratio": 5},
                           distractor_style="drawn")
    real2, dist, perturbed2 = made
    assert "distractor_ratio" not in plain.identity() and dist.identity()["distractor_ratio"] == 5.0
    assert {k: v for k, v in dist.identity().items() if k != "distractor_ratio"} == plain.identity()
    assert (real2.identity(), perturbed2.identity()) == (real.identity(), perturbed.identity())
    assert dist.name == "adaboost / 12 seeds + 20x synthetic (f{seed}, share 0.25) + 5x rendered distractors"
    assert [a.distractor_ratio for a in _added_positives(ws, monkeypatch, plain, dist)] == [0.0, 5.0]
    with pytest.raises(ValueError, match="distractor_ratio"):
        R.Condition("x", "adaboost", seed_count=12, perturb_copies=5, distractor_ratio=5.0)
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).distractor_ratio == "default"
    assert parse(["synthetic", "--distractor-ratio", "2.5", "--out", "x"]).distractor_ratio == 2.5
    _refused(parse, ["synthetic", "--distractor-ratio", "-1", "--out", "x"], "--distractor-ratio", capsys)
    # --distractor-style soft: its own cell and name; the drawn style (the default) keeps the key above
    made.clear()
    R.synthetic_comparison(None, detectors=["adaboost"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           realism_keep=(1.0,), **{**PAPER_DRAWS, "distractor_ratio": 5}, distractor_style="soft")
    soft = made[1]
    assert soft.identity() == {**dist.identity(), "distractor_style": "soft"}
    assert soft.name == dist.name.replace("5x rendered", "5x soft rendered")
    assert [a.distractor_style for a in _added_positives(ws, monkeypatch, dist, soft)] == ["drawn", "soft"]
    assert R.Condition("x", "adaboost", seed_count=12, distractor_style="soft").identity() == real.identity()
    with pytest.raises(ValueError, match="distractor_style"):
        R.Condition("x", "adaboost", seed_count=12, synthetic_ratio=20, distractor_ratio=5, distractor_style="cloudy")
    assert parse(["synthetic", "--out", "x"]).distractor_style == "default"
    assert parse(["synthetic", "--distractor-style", "soft", "--out", "x"]).distractor_style == "soft"
    _refused(parse, ["synthetic", "--distractor-style", "cloudy", "--out", "x"], "--distractor-style", capsys)
    _refused(R.main, ["synthetic", "--distractor-style", "soft", "--out", "x"], "--distractor-ratio", capsys)


def test_adaboost_draws_by_its_familys_recipe_and_its_default_cell_is_the_one_trained_with_the_flags(monkeypatch,
                                                                                                    capsys):
    """Unset, AdaBoost's synthetic positives are drawn its family's way (``FAMILY_SYNTHETIC``, with the critic's
    quarter of ``FAMILY_REALISM_KEEP``): its default condition has the key and the name of the cell stops 101-103
    trained with every option given (``adaboost_distractors/run_frame.sh``'s flags), so the stored cells are the
    default's. HOG's and the CNN's stay the paper's (their former keys); an option given wins, the paper's value
    included; real-only and perturbed cells draw nothing and keep their keys."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["adaboost", "hog", "cnn"], seed_count=100, synthetic_ratios=[20],
                           params="f{seed}.json", perturb_copies=[5])
    (ada_real, ada, ada_perturbed), (_, hog, _), (_, cnn, _) = made[:3], made[3:6], made[6:]
    flags = R.Condition("x", "adaboost", seed_count=100, params="f{seed}.json", synthetic_ratio=20.0,
                        realism_keep=0.25, realism_features="weak_learners", quantize="native_scale",
                        pose_sampling="fitted_at_seed", shape_variation=0.3, distractor_ratio=5.0,
                        distractor_style="soft")
    assert ada.identity() == flags.identity()
    assert ada.name == ("adaboost / 100 seeds + 20x synthetic (f{seed}, fitted poses at the seeds' offsets, share 0.25, "
                        "shapes varied 0.3, 8-bit at native scale, the 25% least synthetic of 4x drawn of each seed to "
                        "a weak-learner critic) + 5x soft rendered distractors")
    assert ada_real.identity() == R.Condition("x", "adaboost", seed_count=100).identity()
    assert "distractor_ratio" not in ada_perturbed.identity() and "quantize" not in ada_perturbed.identity()
    for cond, kind in ((hog, "hog"), (cnn, "cnn")):
        paper = R.Condition("x", kind, seed_count=100, params="f{seed}.json", synthetic_ratio=20.0,
                            pose_sampling="uniform", shape_variation=0.0, quantize=False, distractor_ratio=0.0,
                            realism_features="hog")
        assert cond.identity() == paper.identity()
        assert not {"pose_sampling", "shape_variation", "quantize", "distractor_ratio"} & set(cond.identity())
    made.clear()  # the paper's draws asked for AdaBoost: the key its synthetic cells had before stop 104
    R.synthetic_comparison(None, detectors=["adaboost"], seed_count=100, synthetic_ratios=[20], params="f{seed}.json",
                           realism_keep=(1.0,), **PAPER_DRAWS)
    assert made[1].name == "adaboost / 100 seeds + 20x synthetic (f{seed}, share 0.25)"
    assert not {"pose_sampling", "shape_variation", "quantize", "distractor_ratio", "realism_keep",
                "realism_features"} & set(made[1].identity())
    made.clear()  # one option given: the rest stays the family's; an object box keeps the fitted rotations only
    R.synthetic_comparison(None, detectors=["adaboost"], seed_count=100, synthetic_ratios=[20], params="f{seed}.json",
                           quantize=(False,), object_box=("seed",))
    assert made[1].identity() == {**{k: v for k, v in flags.identity().items() if k != "quantize"},
                                  "pose_sampling": "fitted", "object_box": "seed"}
    # the command line: "default" is the family's, parsed as such
    parse = R.build_parser().parse_args
    args = parse(["synthetic", "--out", "x"])
    assert (args.pose_sampling, args.shape_variation, args.quantize, args.realism_features, args.distractor_ratio,
            args.distractor_style) == (["default"], ["default"], ["default"], "default", "default", "default")
    assert parse(["synthetic", "--shape-variation", "default", "0.3", "--out", "x"]).shape_variation == [
        "default", 0.3]
    _refused(parse, ["synthetic", "--shape-variation", "wide", "--out", "x"], "--shape-variation", capsys)
    _refused(R.main, ["synthetic", "--detectors", "hog", "--distractor-style", "soft", "--out", "x"],
             "--distractor-ratio", capsys)


def test_realism_keep_is_a_condition_of_its_own_and_the_familys_default(ws, monkeypatch, capsys):
    """``--realism-keep 1 0.25`` makes a condition per value (named with the fraction kept and the draw,
    ``realism_keep`` in its key and its training's ``AddedPositives``); 1 keeps every former key and name; the
    default is the family's (HOG a quarter, resolved into the key; AdaBoost and the CNN 1); a value out of (0, 1] is
    refused."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           realism_keep=(1.0, 0.25, None))
    real, plain, kept = made  # None is HOG's 0.25: one condition
    assert "realism_keep" not in plain.identity() and kept.identity()["realism_keep"] == 0.25
    assert "realism_keep" not in real.identity() and real.realism_keep == 1.0  # no synthetic positive to filter
    assert kept.identity()["realism_selection"] == "seed"  # the default selection (stop 83)
    assert {k: v for k, v in kept.identity().items() if k not in ("realism_keep", "realism_selection")} \
        == plain.identity()
    assert plain.name == "hog / 12 seeds + 20x synthetic (f{seed})"
    assert kept.name == "hog / 12 seeds + 20x synthetic (f{seed}, the 25% least synthetic of 4x drawn of each seed)"
    assert R.Condition("x", "hog", seed_count=12, params="f{seed}.json", synthetic_ratio=20.0).identity() \
        == kept.identity()
    assert [a.realism_keep for a in _added_positives(ws, monkeypatch, plain, kept)] == [1.0, 0.25]
    made.clear()
    R.synthetic_comparison(None, detectors=["adaboost", "cnn"], seed_count=12, synthetic_ratios=[20],
                           params="f{seed}.json")  # AdaBoost's quarter is part of its recipe (FAMILY_SYNTHETIC)
    assert [c.realism_keep for c in made] == [1.0, 0.25, 1.0, 1.0]
    assert [("realism_keep" in c.identity()) for c in made] == [False, True, False, False]
    assert R.Condition("x", "hog", seed_count=1, synthetic_ratio=20.0).realism_keep == 1.0  # one seed: no critic
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).realism_keep == ["default"]
    assert parse(["synthetic", "--realism-keep", "1", "default", "0.5", "--out", "x"]).realism_keep == [1.0, "default",
                                                                                                     0.5]
    with pytest.raises(SystemExit) as e:
        parse(["synthetic", "--realism-keep", "1.5", "--out", "x"])
    assert e.value.code == 2 and "--realism-keep" in capsys.readouterr().err
    with pytest.raises(ValueError, match="realism_keep"):
        R.synthetic_comparison(None, detectors=["hog"], synthetic_ratios=[20], params="f.json", realism_keep=(0.0,))


def test_realism_selection_makes_a_condition_per_value_only_where_the_critic_keeps_a_fraction(ws, monkeypatch,
                                                                                              capsys):
    """``--realism-selection set seed`` with ``--realism-keep 1 0.25``: every draw once (nothing is selected), the
    quarter twice; the set selection keeps stop 82's key and name, the seed selection (the default since stop 83)
    adds ``realism_selection`` to the key and "of each seed" to the name; both reach the training's
    ``AddedPositives``."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           realism_keep=(1.0, 0.25), realism_selection=("set", "seed"))
    real, plain, by_set, by_seed = made
    assert "realism_selection" not in plain.identity() and plain.realism_selection == "set"
    assert by_seed.identity() == R.Condition("x", "hog", seed_count=12, params="f{seed}.json",
                                             synthetic_ratio=20.0).identity()  # the default (stop 83)
    assert by_seed.identity() == {**by_set.identity(), "realism_selection": "seed"}  # set: stop 82's key
    assert by_set.name == "hog / 12 seeds + 20x synthetic (f{seed}, the 25% least synthetic of 4x drawn)"
    assert by_seed.name == by_set.name[:-1] + " of each seed)"
    assert [(a.realism_keep, a.realism_selection) for a in _added_positives(ws, monkeypatch, by_set, by_seed)] == [
        (0.25, "set"), (0.25, "seed")]
    # every draw: nothing selected, one key whatever the selection
    assert R.Condition("x", "hog", seed_count=12, params="f{seed}.json", synthetic_ratio=20.0, realism_keep=1.0,
                       realism_selection="seed").identity() == plain.identity()
    with pytest.raises(ValueError, match="realism_selection"):
        R.Condition("x", "hog", seed_count=12, synthetic_ratio=20.0, realism_selection="video")
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).realism_selection == ["seed"]
    assert parse(["synthetic", "--realism-selection", "seed", "set", "--out", "x"]).realism_selection == ["seed", "set"]
    # the lazy form (SyntheticObjectDataset's critic): a key and a name of its own
    made.clear()
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           realism_keep=(0.25,), realism_selection=("item",))
    by_item = made[1]
    assert by_item.identity() == {**by_set.identity(), "realism_selection": "item"}
    assert by_item.name == "hog / 12 seeds + 20x synthetic (f{seed}, the least synthetic of 4 candidates per patch)"
    assert [a.realism_selection for a in _added_positives(ws, monkeypatch, by_item)] == ["item"]
    with pytest.raises(SystemExit) as e:
        parse(["synthetic", "--realism-selection", "video", "--out", "x"])
    assert e.value.code == 2 and "--realism-selection" in capsys.readouterr().err


def test_realism_features_name_the_critic_and_keep_the_former_keys(ws, monkeypatch, capsys):
    """``--realism-features weak_learners`` gives every condition that keeps under 1 a critic in AdaBoost's features
    (``realism_features`` in its key, its name and its training's ``AddedPositives``); HOG's, the default, keeps every
    former key and name; every draw has no critic, so one key; the lazy selection, which scores in HOG, is refused."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["adaboost"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           realism_keep=(1.0, 0.25), realism_features="weak_learners", **PAPER_DRAWS)
    real, every, wl = made
    assert "realism_features" not in every.identity() and every.realism_features == "hog"
    assert wl.identity() == {**R.Condition("x", "adaboost", seed_count=12, params="f{seed}.json",
                                           synthetic_ratio=20.0, realism_keep=0.25, realism_features="hog",
                                           pose_sampling="uniform", shape_variation=0.0, quantize=False,
                                           distractor_ratio=0.0).identity(),
                             "realism_features": "weak_learners"}
    assert wl.name == ("adaboost / 12 seeds + 20x synthetic (f{seed}, share 0.25, the 25% least synthetic of 4x drawn "
                       "of each seed to a weak-learner critic)")
    assert [(a.realism_keep, a.realism_features) for a in _added_positives(ws, monkeypatch, every, wl)] == [
        (1.0, "hog"), (0.25, "weak_learners")]
    made.clear()
    R.synthetic_comparison(None, detectors=["adaboost", "hog"], seed_count=12, synthetic_ratios=[20],
                           params="f{seed}.json", realism_keep=(0.25,), realism_features="hog", **PAPER_DRAWS)
    assert "realism_features" not in made[1].identity() and "weak-learner" not in made[1].name
    made.clear()  # unset: each family's own (AdaBoost's weak learners, HOG's own features)
    R.synthetic_comparison(None, detectors=["adaboost", "hog"], seed_count=12, synthetic_ratios=[20],
                           params="f{seed}.json", realism_keep=(0.25,), **PAPER_DRAWS)
    assert [c.realism_features for c in made] == ["hog", "weak_learners", "hog", "hog"]
    with pytest.raises(ValueError, match="realism_features"):
        R.Condition("x", "hog", seed_count=12, synthetic_ratio=20.0, realism_features="cnn")
    with pytest.raises(ValueError, match="'item' scores candidates in HOG"):
        R.Condition("x", "adaboost", seed_count=12, synthetic_ratio=20.0, realism_keep=0.25,
                    realism_selection="item", realism_features="weak_learners")
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).realism_features == "default"
    assert parse(["synthetic", "--realism-features", "weak_learners", "--out", "x"]).realism_features == "weak_learners"
    with pytest.raises(SystemExit) as e:
        parse(["synthetic", "--realism-features", "cnn", "--out", "x"])
    assert e.value.code == 2 and "--realism-features" in capsys.readouterr().err


def test_background_sampling_is_a_condition_of_its_own_and_keeps_the_former_keys(ws, monkeypatch, capsys):
    """``--background-sampling other`` adds a condition per synthetic ratio whose objects sit on other seeds'
    backgrounds (named so, ``background_sampling`` in its key and in the ``AddedPositives`` its training gets); the
    paper's, the default, keeps every former key and name; a value repeated makes one condition."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           background_sampling=("seed", "other", "other"), realism_keep=(1.0,))  # the former names
    real, own, other = made
    assert "background_sampling" not in own.identity() and other.identity()["background_sampling"] == "other"
    assert {k: v for k, v in other.identity().items() if k != "background_sampling"} == own.identity()
    assert own.name == "hog / 12 seeds + 20x synthetic (f{seed})"
    assert other.name == "hog / 12 seeds + 20x synthetic (f{seed}, backgrounds of other seeds)"
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).background_sampling == ["default"]
    assert parse(["synthetic", "--background-sampling", "seed", "other", "--out", "x"]).background_sampling == [
        "seed", "other"]
    with pytest.raises(SystemExit) as e:
        parse(["synthetic", "--background-sampling", "random", "--out", "x"])
    assert e.value.code == 2 and "--background-sampling" in capsys.readouterr().err
    assert [a.background_sampling for a in _added_positives(ws, monkeypatch, own, other)] == ["seed", "other"]


def test_object_box_share_mixes_the_two_framings_and_keeps_the_former_keys(ws, monkeypatch, capsys):
    """``--object-box fit --object-box-share 0.5``: the framed condition frames half its objects (named so, the share
    in its key and in the ``AddedPositives`` its training gets); the paper's framing ignores the share; the default 1
    keeps every former key and name; a share without a framing is a usage error."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           object_box=(None, "fit"), realism_keep=(1.0,))  # every draw: the former names
    _, paper, framed = made
    made.clear()
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           object_box=(None, "fit"), object_box_share=0.5, realism_keep=(1.0,))
    _, paper_mix, mixed = made
    assert paper_mix.identity() == paper.identity() and paper_mix.name == paper.name
    assert "object_box_share" not in framed.identity() and mixed.identity()["object_box_share"] == 0.5
    assert {k: v for k, v in mixed.identity().items() if k != "object_box_share"} == framed.identity()
    assert framed.name == "hog / 12 seeds + 20x synthetic (f{seed}, framed as the seeds (fit))"
    assert mixed.name == "hog / 12 seeds + 20x synthetic (f{seed}, framed as the seeds (fit) for 50%)"
    assert [a.object_box_share for a in _added_positives(ws, monkeypatch, framed, mixed)] == [1.0, 0.5]
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).object_box_share == 1.0
    for bad in ("0", "1.5", "half"):
        with pytest.raises(SystemExit) as e:
            parse(["synthetic", "--object-box-share", bad, "--out", "x"])
        assert e.value.code == 2 and "--object-box-share" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        R.main(["synthetic", "--object-box-share", "0.5", "--out", "x"])
    assert e.value.code == 2 and "give --object-box seed or fit" in capsys.readouterr().err
    with pytest.raises(ValueError, match="give an object_box"):
        R.Condition("x", "hog", synthetic_ratio=20.0, params="f.json", object_box_share=0.5)
    from synthaug.detectors.video_training import AddedPositives

    with pytest.raises(ValueError, match="object_box_share must be a fraction in"):
        AddedPositives(object_box="fit", object_box_share=0.0)


def test_synthetic_downscaled_copies_join_each_synthetic_condition(ws, monkeypatch, capsys):
    """``--synthetic-downscaled-copies K``: every synthetic condition also holds K downscaled copies of each real seed
    (named so, both in its key and in the ``AddedPositives`` its training gets), beside the copies alone
    (``--downscaled-copies K``) and the synthetic data alone; 0, the default, keeps every former key and name."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           realism_keep=(1.0,))  # every draw: the former names
    _, alone = made
    made.clear()
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           downscaled_copies=[5], synthetic_downscaled=5, realism_keep=(1.0,))
    real, both, copies = made
    assert both.name == "hog / 12 seeds + 20x synthetic (f{seed}) + 5x downscaled"
    assert copies.name == "hog / 12 seeds + 5x downscaled" and copies.synthetic_ratio == 0
    assert (both.synthetic_ratio, both.downscaled_copies) == (20.0, 5)
    assert {k: v for k, v in both.identity().items() if k != "downscaled_copies"} == alone.identity()
    assert "downscaled_copies" not in alone.identity() and "downscaled_copies" not in real.identity()
    added = _added_positives(ws, monkeypatch, alone, both)
    assert [(a.synthetic_ratio, a.downscaled_copies) for a in added] == [(20.0, 0), (20.0, 5)]
    parse = R.build_parser().parse_args
    assert parse(["synthetic", "--out", "x"]).synthetic_downscaled_copies == 0
    assert parse(["synthetic", "--synthetic-downscaled-copies", "5", "--out", "x"]).synthetic_downscaled_copies == 5
    _refused(parse, ["synthetic", "--synthetic-downscaled-copies", "-1", "--out", "x"], "--synthetic-downscaled-copies",
             capsys)


def test_background_sampling_default_is_the_familys_and_resolved_into_the_key(ws, monkeypatch):
    """None (``--background-sampling default``): each family's own, resolved into the condition as the effects are,
    so a CNN's default cell is the cell of other seeds' backgrounds (its stored cells read back) and HOG's default
    keeps the paper's key; the CNN with ``seed`` keeps the key its cells had before the default; real-only cells and a
    one-seed set keep their own backgrounds; a value repeated or equal to the default makes one condition."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["cnn", "hog"], seed_count=100, synthetic_ratios=[20],
                           params="f{seed}.json", background_sampling=(None, "seed", "other"))
    syn = [c for c in made if c.synthetic_ratio]
    assert [(c.kind, c.background_sampling) for c in syn] == [("cnn", "other"), ("cnn", "seed"), ("hog", "seed"),
                                                                ("hog", "other")]
    blurs = ", without boundary_blur and motion_blur"
    assert syn[0].name == f"cnn / 100 seeds + 20x synthetic (f{{seed}}{blurs}, backgrounds of other seeds)"
    assert syn[1].name == f"cnn / 100 seeds + 20x synthetic (f{{seed}}{blurs})"
    cnn_default = R.Condition("x", "cnn", seed_count=100, params="f{seed}.json", synthetic_ratio=20.0)
    cnn_other = R.Condition("x", "cnn", seed_count=100, params="f{seed}.json", synthetic_ratio=20.0,
                            background_sampling="other")
    assert cnn_default.identity() == cnn_other.identity() == syn[0].identity()
    assert cnn_default.identity()["background_sampling"] == "other"
    assert "background_sampling" not in syn[1].identity() and "background_sampling" not in syn[2].identity()
    assert R.Condition("x", "hog", seed_count=100, params="f{seed}.json", synthetic_ratio=20.0).identity() == \
        syn[2].identity()
    assert "background_sampling" not in R.Condition("x", "cnn").identity()  # real only: nothing drawn
    assert R.Condition("x", "cnn", seed_count=1, params="f.json", synthetic_ratio=20.0).background_sampling == "seed"
    made.clear()
    R.synthetic_comparison(None, detectors=["cnn"], seed_count=100, synthetic_ratios=[20], params="f{seed}.json",
                           background_sampling=(None, "other"))
    assert [c.background_sampling for c in made if c.synthetic_ratio] == ["other"]
    # the cell's training gets the resolved value
    assert [a.background_sampling for a in _added_positives(ws, monkeypatch, syn[0], syn[1])] == ["other", "seed"]
    args = R.build_parser().parse_args(["synthetic", "--background-sampling", "default", "seed", "--out", "x"])
    assert args.background_sampling == ["default", "seed"]


def test_at_seed_pose_sampling_is_a_condition_of_its_own_and_refuses_an_object_box(ws, monkeypatch, capsys):
    """``--pose-sampling uniform_at_seed fitted_at_seed``: one condition each (named so, ``pose_sampling`` in the key
    and in the ``AddedPositives`` its training gets); the former names and keys unchanged; with an object box,
    which centres the object itself, a usage error."""
    made = []
    monkeypatch.setattr(R, "_run_into", _record_in_table_order(made))
    R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                           pose_sampling=("uniform", "fitted", "uniform_at_seed", "fitted_at_seed"),
                           realism_keep=(1.0,))  # every draw: the former names
    real, uniform, fitted, at, fitted_at = made
    assert "pose_sampling" not in uniform.identity() and fitted.identity()["pose_sampling"] == "fitted"
    assert at.identity()["pose_sampling"] == "uniform_at_seed"
    assert {k: v for k, v in at.identity().items() if k != "pose_sampling"} == uniform.identity()
    assert uniform.name == "hog / 12 seeds + 20x synthetic (f{seed})"
    assert fitted.name == "hog / 12 seeds + 20x synthetic (f{seed}, fitted poses)"
    assert at.name == "hog / 12 seeds + 20x synthetic (f{seed}, at the seeds' offsets)"
    assert fitted_at.name == "hog / 12 seeds + 20x synthetic (f{seed}, fitted poses at the seeds' offsets)"
    assert [a.pose_sampling for a in _added_positives(ws, monkeypatch, uniform, at)] == ["uniform", "uniform_at_seed"]
    with pytest.raises(ValueError, match="centres it"):
        R.synthetic_comparison(None, detectors=["hog"], seed_count=12, synthetic_ratios=[20], params="f{seed}.json",
                               pose_sampling=("uniform_at_seed",), object_box=(None, "seed"))
    with pytest.raises(SystemExit) as e:
        R.main(["synthetic", "--pose-sampling", "uniform_at_seed", "--object-box", "none", "fit", "--out", "x"])
    assert e.value.code == 2 and "--pose-sampling" in capsys.readouterr().err
    from synthaug.detectors.video_training import AddedPositives

    with pytest.raises(ValueError, match="pose_sampling must be one of"):
        AddedPositives(pose_sampling="kde")
    with pytest.raises(ValueError, match="choose one"):
        AddedPositives(pose_sampling="fitted_at_seed", object_box="fit")


@pytest.mark.slow
def test_dcnn_refit_cells_refit_against_each_rounds_network_and_redraw_the_synthetic_positives(ws, monkeypatch, capsys):
    """The d_CNN refit under the protocol (the paper's refit experiment, issue 16 item 5): a cell of its own key;
    after round 0 each seed's fit is refitted with round 0's CNN as the distance (the fit's own options, its seed
    moved by 1) and round 1 trains on synthetic positives redrawn from that file with the same draws; the cell
    records the refit. Refused for a family without a network, and at the command line."""
    import synthaug.detectors.video_training as VT
    from synthaug.params import CaptureParams

    drawn = []
    real_draw = VT.synthetic_positives

    grounds = []

    def spy(ss, mesh, fit, n, **kw):
        drawn.append((str(fit), n, kw["seed"]))
        grounds.append(kw["background_sampling"])
        return real_draw(ss, mesh, fit, n, **kw)

    monkeypatch.setattr(VT, "synthetic_positives", spy)
    fit_opts = {"budget": 30, "step_deg": 30.0, "sprite_size": 32, "init": "uniform"}
    opts = dataclasses.replace(FAST, cnn_epochs=2, cnn_finetune_epochs=1)
    runner = make_runner(ws, options=opts)
    res = R.synthetic_comparison(runner, detectors=["cnn"], seed_count=6, synthetic_ratios=[2], fit_distance="eucl",
                                 fit_options=fit_opts, effects_off=((),), dcnn_refit=(True,), seeds=[0, 1],
                                 out=ws["root"] / "refit")
    refit = "cnn / 6 seeds + 2x synthetic (eucl, d_CNN refit every round, backgrounds of other seeds)"
    assert list(res["cnn"]) == ["cnn / 6 seeds", refit]
    assert set(grounds) == {"other"}  # the CNN's backgrounds, kept when the refitted file redraws
    cond = R.Condition(refit, "cnn", seed_count=6, synthetic_ratio=2.0, fit_distance="eucl",
                       fit_options=tuple(sorted(fit_opts.items())), effects_off=(), dcnn_refit=True)
    assert cond.identity()["dcnn_refit"] is True and "dcnn_refit" not in dataclasses.replace(cond, dcnn_refit=False).identity()
    cache = CellCache(Path(ws["paths"].work_dir) / "cells")
    for seed in (0, 1):
        cell = cache.get_or_compute(runner.identity(cond, seed), lambda: pytest.fail("refit cell not cached"))
        (rec,) = cell["train"]["synthetic"]["refits"]  # one mining round: one refit, after round 0
        start = Path(ws["paths"].work_dir) / "fits" / f"drone_6_seed{seed}_eucl.json"
        assert rec["after_round"] == 0 and Path(rec["params"]).parent == cache.root / "refits"
        _, _, meta = CaptureParams.load_with_extra(rec["params"])
        _, _, start_meta = CaptureParams.load_with_extra(start)
        assert meta["config"] == {**start_meta["config"], "distance": "cnn", "seed": start_meta["config"]["seed"] + 1}
        # the refitted file drew round 1's synthetic positives, with the same count and draw seed as round 0's
        assert [d for d in drawn if d[0] == rec["params"]] == [(rec["params"], 12, seed + 2)]
        assert (str(start), 12, seed + 2) in drawn
    with pytest.raises(ValueError, match="no network"):
        R.synthetic_comparison(runner, detectors=["cnn", "hog"], seed_count=6, synthetic_ratios=[2], dcnn_refit=(True,))
    assert R.build_parser().parse_args(["synthetic", "--out", "x"]).dcnn_refit == ["off"]
    with pytest.raises(SystemExit) as e:
        R.main(["synthetic", "--detectors", "hog", "cnn", "--dcnn-refit", "on", "--out", "x"])
    assert e.value.code == 2 and "--dcnn-refit" in capsys.readouterr().err


def test_box_calibration_scores_the_stored_detector_with_its_own_correction(ws, curve, monkeypatch, capsys):
    """``box_calibration``: a new cell with the stored detector (no training), whose boxes are those of the
    detector with :func:`calibrate_boxes` fitted on its training videos' frames at that stride."""
    from synthaug.detectors.base import load_detector
    from synthaug.detectors.box_calibration import CALIBRATION_VERSION, CalibratedBoxRegressor, calibrate_boxes
    from synthaug.detectors.sliding import detect_multiscale
    from synthaug.detectors.frames import VideoFrames
    from synthaug.evaluate.matching import match_videos
    from synthaug.evaluate.videos import detect_on_eval_set, refine_detections

    def no_training(*a, **k):
        raise AssertionError("a stored detector was trained again")

    monkeypatch.setattr(R, "train_from_videos", no_training)
    c = R.Condition("hog / 6 seeds", "hog", seed_count=6)
    plain = make_runner(ws, scale_check=False, patches=False)
    cal = make_runner(ws, scale_check=False, patches=False, options=dataclasses.replace(FAST, box_calibration=1))
    assert cal.identity(c, 0)["options"]["box_calibration"] == {"stride": 1, "version": CALIBRATION_VERSION}
    assert "box_calibration" not in plain.identity(c, 0)["options"]
    assert cal.training_identity(c, 0) == plain.training_identity(c, 0)
    res = cal.run(c, seeds=[0])[1.0]
    cell = CellCache(Path(ws["paths"].work_dir) / "cells").get(cal.identity(c, 0))
    assert cell["detector_read_back"] is True and cell["box_calibration"]["pairs"] >= 20
    det = load_detector(CellCache(Path(ws["paths"].work_dir) / "cells" / "detectors").path(
        plain.training_identity(c, 0)).with_suffix(".pt"))
    nms, top = ws["proto"].detection.nms_iou, ws["proto"].detection.max_detections
    det.box_regressor = calibrate_boxes(det, VideoFrames(ws["paths"].videos_dir, ws["paths"].labels_dir,
                                                         positive=TRAIN, stride=1),
                                        scales=(1.0, 0.8), nms_iou=nms, max_detections=top,
                                        detect=detect_multiscale)
    assert isinstance(det.box_regressor, CalibratedBoxRegressor)
    assert det.box_regressor.meta["coef"] == cell["box_calibration"]["coef"]
    es = cal.eval_set(1.0)
    raw = detect_on_eval_set(det, es, scales=(1.0, 0.8), nms_iou=nms, max_detections=top, refine_boxes=False)
    ref = match_videos(es.stems, refine_detections(det, es, raw, nms_iou=nms), es.boxes, ws["proto"])
    assert [v.tp.tolist() for v in res.seeds[0].videos] == [v.tp.tolist() for v in ref]
    assert [v.det_size.tolist() for v in res.seeds[0].videos] == [v.det_size.tolist() for v in ref]
    with pytest.raises(ValueError, match="box_calibration"):
        TrainOptions(box_calibration=-1)
    args = R.build_parser().parse_args(["synthetic", "--box-calibration", "15", "--out", "x"])
    assert R.train_options(args).box_calibration == 15
    inv = make_runner(ws, scale_check=False, patches=False,
                      options=dataclasses.replace(FAST, box_calibration=1, box_calibration_form="inverse"))
    assert inv.identity(c, 0)["options"]["box_calibration_form"] == "inverse"  # a cell of its own ...
    assert "box_calibration_form" not in cal.identity(c, 0)["options"]  # (the default keeps the keys of before)
    assert inv.training_identity(c, 0) == plain.training_identity(c, 0)  # ... scoring the same stored detector
    args = R.build_parser().parse_args(["synthetic", "--box-calibration-form", "inverse", "--out", "x"])
    assert R.train_options(args).box_calibration_form == "inverse"
    with pytest.raises(ValueError, match="box_calibration_form"):
        TrainOptions(box_calibration_form="median")
    with pytest.raises(SystemExit):
        R.build_parser().parse_args(["synthetic", "--box-calibration", "-2", "--out", "x"])
    capsys.readouterr()


def test_a_long_condition_name_gets_a_file_name_the_file_system_takes(tmp_path):
    """A cell's JSON is named by its condition: names whose stem passes ``SLUG_MAX`` (AdaBoost's default at 100 seeds
    with native-scale rounding) are cut and end in a hash of the whole name, distinct per name, and the atomic write
    (a ``.NAME.XXXXXXXX.tmp`` beside it) succeeds; shorter names keep their stems."""
    from synthaug.params import atomic_write_text

    base = ("adaboost / 100 seeds + 20x synthetic (hog, twin_prop_airplane, fitted poses at the seeds' offsets, share "
            "0.25, shapes varied 0.3, 8-bit{}, the 25% least synthetic of 4x drawn of each seed to a weak-learner "
            "critic) + 5x soft rendered distractors")
    short, native, other = base.format(""), base.format(" at native scale"), base.format(" at native scale!")
    assert R._slug(short) == ("adaboost_100_seeds_20x_synthetic_hog_twin_prop_airplane_fitted_poses_at_the_seeds_"
                              "offsets_share_0.25_shapes_varied_0.3_8_bit_the_25_least_synthetic_of_4x_drawn_of_each_"
                              "seed_to_a_weak_learner_critic_5x_soft_rendered_distractors")  # the stored cells' names
    assert len(R._slug(short)) <= R.SLUG_MAX < len(native)
    stems = {R._slug(native), R._slug(other)}
    assert len(stems) == 2 and all(len(s) == R.SLUG_MAX for s in stems)
    assert R._slug(native).startswith(R._slug(short)[:100])
    for stem in stems:
        atomic_write_text(tmp_path / f"{stem}_x0.51.json", "{}")
        assert (tmp_path / f"{stem}_x0.51.json").read_text() == "{}"
