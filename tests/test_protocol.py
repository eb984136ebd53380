"""The evaluation protocol: its file, per-video matching, size buckets vs pycocotools, results, the table,
the scale check and the patch protocol on tiny generated data."""

from __future__ import annotations

import contextlib
import copy
import io
import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from synthaug.evaluate.ap import evaluate_detections, match_detections
from synthaug.evaluate.matching import match_video, match_videos
from synthaug.evaluate.patches import PatchVideoScores, patch_eval_set, patch_metrics, score_patch_set
from synthaug.evaluate.protocol import (
    DEFAULT_PROTOCOL,
    BootstrapSpec,
    Protocol,
    ProtocolError,
    SizeBucket,
    example_protocol_dict,
    load_protocol,
    split_videos,
)
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.summary import report_table, summarize_conditions
from synthaug.evaluate.videos import scale_eval_set, scale_frame

REPO = Path(__file__).resolve().parents[1]


def proto(**overrides) -> Protocol:
    return Protocol.from_dict(example_protocol_dict(**overrides))


# =========================================================================== the protocol file
def test_committed_protocol_file() -> None:
    p = load_protocol(REPO / "configs" / "protocol" / "halmstad_v1.json")
    assert DEFAULT_PROTOCOL == REPO / "configs" / "protocol" / "halmstad_v1.json"
    assert (p.name, p.version, p.min_training_seeds) == ("halmstad_v1", 1, 3)
    assert (p.test.split, p.test.frame_stride, p.val.split, p.val.frame_stride) == ("test", 5, "val", 5)
    assert p.iou_thresholds == (0.5, 0.3) and p.main_iou == 0.5
    assert [b.to_list() for b in p.size_buckets] == [[0, 24], [24, 48], [48, 96], [96, None]]
    assert p.scale_check == (2.0, 0.75)
    assert (p.bootstrap.resamples, p.bootstrap.seed, p.bootstrap.ci) == (2000, 0, 0.95)
    assert (p.patch.negatives_per_positive, p.patch.seed, p.patch.patch_size, p.patch.object_fraction) == (20, 0, 40, 0.7)
    assert (REPO / p.split_file).is_file()
    # the committed file is the example dict plus a description: same fingerprint
    assert p.fingerprint() == proto().fingerprint()
    assert len(p.fingerprint()) == 16 and int(p.fingerprint(), 16) >= 0


def test_fingerprint_is_canonical(tmp_path: Path) -> None:
    d = example_protocol_dict()
    # other key order, other spacing, ints for floats, a description: same protocol
    shuffled = {k: d[k] for k in reversed(list(d))}
    shuffled["scale_check"] = [2, 0.75]
    shuffled["description"] = "anything"
    f = tmp_path / "p.json"
    f.write_text(json.dumps(shuffled, indent=4))
    assert load_protocol(f).fingerprint() == proto().fingerprint()
    # the defaults of optional fields are part of the canonical form
    d2 = example_protocol_dict()
    del d2["detection"], d2["patch"]["max_tries"]
    assert Protocol.from_dict(d2).fingerprint() == proto().fingerprint()
    # anything measured differently: another fingerprint
    for change in ({"min_training_seeds": 5}, {"iou_thresholds": [0.5]}, {"scale_check": [2.0]},
                   {"bootstrap": {"resamples": 1000, "seed": 0, "ci": 0.95}},
                   {"test": {"split": "test", "frame_stride": 10}}, {"version": 2}):
        assert proto(**change).fingerprint() != proto().fingerprint(), change
    # round trip
    p = proto()
    assert Protocol.from_dict(p.to_dict()) == p


def _mutate(path: str, value):
    d = copy.deepcopy(example_protocol_dict())
    keys = path.split(".")
    target = d
    for k in keys[:-1]:
        target = target[k]
    if value is KeyError:
        del target[keys[-1]]
    else:
        target[keys[-1]] = value
    return d


@pytest.mark.parametrize("path, value, field", [
    ("name", KeyError, "name"),
    ("name", "", "name"),
    ("version", 0, "version"),
    ("version", True, "version"),
    ("test.frame_stride", 0, "test.frame_stride"),
    ("test.frame_stride", 2.5, "test.frame_stride"),
    ("val.split", "validation", "val.split"),
    ("test", [5], "test"),
    ("min_training_seeds", "3", "min_training_seeds"),
    ("iou_thresholds", [], "iou_thresholds"),
    ("iou_thresholds", [0.5, 1.5], "iou_thresholds[1]"),
    ("iou_thresholds", [0.5, 0.5], "iou_thresholds"),
    ("size_buckets_px", [[0, 24], [20, 48]], "size_buckets_px[1]"),
    ("size_buckets_px", [[0, None], [24, 48]], "size_buckets_px[0][1]"),
    ("size_buckets_px", [[30, 24]], "size_buckets_px[0][1]"),
    ("size_buckets_px", [[0, 24, 48]], "size_buckets_px[0]"),
    ("scale_check", [2.0, -1], "scale_check[1]"),
    ("scale_check", 2.0, "scale_check"),
    ("bootstrap.ci", 1.0, "bootstrap.ci"),
    ("bootstrap.resamples", 0, "bootstrap.resamples"),
    ("bootstrap.seed", -1, "bootstrap.seed"),
    ("bootstrap.sed", 0, "bootstrap.sed"),
    ("patch.negatives_per_positive", 0, "patch.negatives_per_positive"),
    ("patch.object_fraction", 1.5, "patch.object_fraction"),
    ("patch.seed", KeyError, "patch.seed"),
    ("detection.nms_iou", 0.0, "detection.nms_iou"),
    ("bootsrap", {}, "bootsrap"),
])
def test_bad_fields_are_named(path: str, value, field: str) -> None:
    with pytest.raises(ProtocolError, match=re.escape(f"field '{field}'")):
        Protocol.from_dict(_mutate(path, value))


def test_bad_files(tmp_path: Path) -> None:
    with pytest.raises(ProtocolError, match="not found"):
        load_protocol(tmp_path / "missing.json")
    (tmp_path / "bad.json").write_text("{nope")
    with pytest.raises(ProtocolError, match="not valid JSON"):
        load_protocol(tmp_path / "bad.json")
    (tmp_path / "list.json").write_text("[]")
    with pytest.raises(ProtocolError, match="must be a JSON object"):
        load_protocol(tmp_path / "list.json")


def test_split_videos() -> None:
    p = load_protocol()
    drones = split_videos(p, "test", split_file=REPO / "configs" / "splits" / "halmstad.json", class_name="drone")
    assert drones and all(s.startswith("V_DRONE") for s in drones)
    assert set(drones) <= set(split_videos(p, "test", split_file=REPO / "configs" / "splits" / "halmstad.json"))
    with pytest.raises(ValueError, match="no test video"):
        split_videos(p, "test", split_file=REPO / "configs" / "splits" / "halmstad.json", class_name="zeppelin")


# =========================================================================== per-video matching
def _random_video(rng: np.random.Generator, n_frames: int = 12, *, square: bool = False, cell: float = 160.0,
                  size_range: tuple[float, float] = (12.0, 80.0)) -> tuple[list[np.ndarray], list[np.ndarray | None]]:
    """Frames with 0-3 objects (one per cell, so no detection reaches the IoU threshold with two),
    jittered detections of them (hits, misses, duplicates) and false alarms; distinct scores."""
    cells = [(cx * cell, cy * cell) for cx in range(4) for cy in range(3)]
    dets, gts = [], []
    for f in range(n_frames):
        n_obj = 0 if f % 5 == 0 else int(rng.integers(1, 4))
        objs = []
        for c in rng.choice(len(cells), size=n_obj, replace=False):
            w = float(np.exp(rng.uniform(*np.log(size_range))))
            h = w if square else float(np.exp(rng.uniform(*np.log(size_range))))
            objs.append([cells[c][0] + rng.uniform(0, cell - w), cells[c][1] + rng.uniform(0, cell - h), w, h])
        g = np.array(objs, float).reshape(-1, 4)
        rows = []
        if f % 7 != 3:
            for x, y, w, h in g:
                for _ in range(int(rng.integers(0, 3))):
                    s = rng.uniform(0.7, 1.4, size=2)
                    if square:
                        s[1] = s[0]
                    rows.append([x + rng.normal(0, 0.15) * w, y + rng.normal(0, 0.15) * h, w * s[0], h * s[1]])
            for _ in range(int(rng.integers(0 if f else 1, 4))):
                w = float(np.exp(rng.uniform(*np.log(size_range))))
                h = w if square else float(np.exp(rng.uniform(*np.log(size_range))))
                rows.append([rng.uniform(0, 4 * cell - w), rng.uniform(0, 3 * cell - h), w, h])
        d = np.array(rows, float).reshape(-1, 4)
        dets.append(np.c_[d, rng.uniform(0, 1, size=len(d))])
        gts.append(None if f % 5 == 0 and f % 2 == 0 else g)  # "no object" both as None and as an empty array
    return dets, gts


def test_match_video_is_match_detections() -> None:
    rng = np.random.default_rng(0)
    dets, gts = _random_video(rng, 20)
    dets[4] = None  # a frame not processed: its objects do not count
    vm = match_video(dets, gts, iou_thresholds=(0.5, 0.3), stem="V")
    for k, t in enumerate((0.5, 0.3)):
        s, tp, n, nf = match_detections(dets, gts, t)
        assert np.array_equal(vm.scores, s) and np.array_equal(vm.tp[k], tp)
        assert vm.n_objects == n and vm.n_frames == nf == 19
        assert np.all(np.isnan(vm.match_size[k][~tp])) and np.all(vm.match_size[k][tp] > 0)
    assert vm.tp[1].sum() >= vm.tp[0].sum() > 3
    # sizes: the detections' longest sides, in the score order
    raw = np.concatenate([d for d in dets if d is not None])
    order = np.argsort(-raw[:, 4], kind="stable")
    np.testing.assert_allclose(vm.det_size, np.maximum(raw[order, 2], raw[order, 3]))
    np.testing.assert_allclose(np.sort(vm.gt_size), np.sort(np.concatenate(
        [np.maximum(g[:, 2], g[:, 3]) for d, g in zip(dets, gts) if d is not None and g is not None])))


def test_pooled_result_ap_is_evaluate_detections_of_all_frames() -> None:
    """A result's AP, recomputed from the per-video lists, is the AP of evaluate_on_videos (all frames pooled)."""
    p = proto()
    rng = np.random.default_rng(1)
    videos = [_random_video(rng, int(rng.integers(3, 10))) for _ in range(5)]
    videos.append(([np.zeros((0, 5))] * 3, [None] * 3))  # a video with nothing at all
    stems = ["V_DRONE_010", "V_DRONE_003", "V_DRONE_107", "V_DRONE_056", "V_DRONE_058", "V_DRONE_200"]
    r = ProtocolResult("c", p)
    r.add_seed(0, videos=match_videos(stems, [d for d, _ in videos], [g for _, g in videos], p))
    assert r.stems == sorted(stems)
    # in sorted stem order, as the result keeps them
    order = np.argsort(stems)
    all_d = [f for i in order for f in videos[i][0]]
    all_g = [f for i in order for f in videos[i][1]]
    for t in (0.5, 0.3):
        assert r.mean_ap(t) == pytest.approx(evaluate_detections(all_d, all_g, t).ap, abs=1e-12)
    assert r.n_objects() == evaluate_detections(all_d, all_g).n_ground_truth


# =========================================================================== size buckets vs pycocotools
def _coco_precision(dets, gts, ious, area_rngs):
    """COCOeval's interpolated precision [T, R, A] (one category, up to 1000 detections per frame)."""
    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval

    images, annotations, results = [], [], []
    for f, (d, g) in enumerate(zip(dets, gts)):
        images.append({"id": f, "width": 640, "height": 480})
        for box in [] if g is None else g:
            annotations.append({"id": len(annotations) + 1, "image_id": f, "category_id": 1, "bbox": [float(v) for v in box],
                                "area": float(box[2] * box[3]), "iscrowd": 0})
        results.extend({"image_id": f, "category_id": 1, "bbox": [float(v) for v in row[:4]], "score": float(row[4])} for row in d)
    with contextlib.redirect_stdout(io.StringIO()):
        coco_gt = COCO()
        coco_gt.dataset = {"images": images, "annotations": annotations, "categories": [{"id": 1, "name": "object"}]}
        coco_gt.createIndex()
        coco_dt = coco_gt.loadRes(results)
        ev = COCOeval(coco_gt, coco_dt, "bbox")
        ev.params.iouThrs = np.array(ious)
        ev.params.maxDets = [1000]
        ev.params.areaRng = area_rngs
        ev.params.areaRngLbl = [str(i) for i in range(len(area_rngs))]
        ev.evaluate()
        ev.accumulate()
    return ev.eval["precision"][:, :, 0, :, 0], ev.params.recThrs


def _interpolated_precision(scores, is_tp, n, rec_thrs):
    """COCO's 101-point sampling of our PR curve (from synthaug.evaluate.ap.precision_recall)."""
    from synthaug.evaluate.ap import precision_recall

    p, r, _ = precision_recall(scores, is_tp, n)
    out = np.zeros(len(rec_thrs))
    if p.size == 0:
        return out
    env = np.maximum.accumulate(p[::-1])[::-1]
    idx = np.searchsorted(r, rec_thrs, side="left")
    ok = idx < r.size
    out[ok] = env[idx[ok]]
    return out


@pytest.mark.parametrize("seed", range(3))
def test_size_buckets_match_pycocotools_area_ranges(seed: int) -> None:
    pytest.importorskip("pycocotools")
    p = proto()
    rng = np.random.default_rng(seed)
    videos = [_random_video(rng, 15, square=True, cell=260.0, size_range=(10.0, 150.0)) for _ in range(3)]
    dets = [f for d, _ in videos for f in d]
    gts = [f for _, g in videos for f in g]
    # the two matching rules agree when no detection reaches the threshold with two objects
    from synthaug.data.boxes import box_iou, xywh_to_xyxy

    for d, g in zip(dets, gts):
        if g is not None and len(g) and len(d):
            assert ((box_iou(xywh_to_xyxy(d[:, :4]), xywh_to_xyxy(g)) >= 0.3).sum(1) <= 1).all()
    scores = np.concatenate([d[:, 4] for d in dets])
    assert np.unique(scores).size == scores.size
    vms = [match_video(d, g, iou_thresholds=p.iou_thresholds, stem=f"v{i}") for i, (d, g) in enumerate(videos)]
    buckets = list(p.size_buckets) + [SizeBucket(0.0, None)]
    area_rngs = [[b.low ** 2, 1e10 if b.high is None else b.high ** 2] for b in buckets]
    coco, rec_thrs = _coco_precision(dets, gts, list(p.iou_thresholds), area_rngs)
    r = ProtocolResult("c", p)
    r.add_seed(0, videos=vms)
    checked = 0
    for a, b in enumerate(buckets):
        for k, t in enumerate(p.iou_thresholds):
            pool = r.pools(t, b)[0]
            s, tp, n = pool.pooled()
            if n == 0:
                assert np.all(coco[k, :, a] == -1)  # COCO: no object in the range
                continue
            ours = _interpolated_precision(s, tp, n, rec_thrs)
            np.testing.assert_allclose(ours, coco[k, :, a], rtol=0, atol=1e-12, err_msg=f"bucket {b.label}, IoU {t}")
            checked += 1
            if k == 0 and b.high is None and b.low == 0:
                # the all-sizes "bucket" is the plain AP
                assert pool.ap() == pytest.approx(evaluate_detections(dets, gts, t).ap, abs=1e-12)
    assert checked >= 8
    # every bucket had objects and some detections of its own
    n_obj = [r.n_objects(b) for b in p.size_buckets]
    assert all(n > 0 for n in n_obj) and sum(n_obj) == r.n_objects()


def test_bucket_semantics_by_hand() -> None:
    p = proto()
    small, big = [10.0, 10.0, 20.0, 20.0], [200.0, 200.0, 60.0, 60.0]
    dets = [np.array([[*small, 0.9], [*big, 0.8], [300.0, 10.0, 60.0, 60.0, 0.7], [400.0, 10.0, 20.0, 20.0, 0.6]])]
    gts = [np.array([small, big, [500.0, 300.0, 30.0, 30.0]])]
    vm = match_video(dets, gts, iou_thresholds=p.iou_thresholds)
    # <24: TP (small), [big TP ignored], [60-px FP ignored], 20-px FP counts; 1 object -> p=1 at r=1 -> AP 1
    s, tp, n = vm.ranking(0.5, p.size_buckets[0])
    assert s.tolist() == [0.9, 0.6] and tp.tolist() == [True, False] and n == 1
    # 48-96: big TP, 60-px FP; 1 object
    s, tp, n = vm.ranking(0.5, p.size_buckets[2])
    assert s.tolist() == [0.8, 0.7] and tp.tolist() == [True, False] and n == 1
    # 24-48: only the missed 30-px object; every detection ignored
    s, tp, n = vm.ranking(0.5, p.size_buckets[1])
    assert s.size == 0 and n == 1
    # ≥96: nothing
    assert vm.ranking(0.5, p.size_buckets[3])[2] == 0


# =========================================================================== results, JSON, table
def _result(p: Protocol, name: str, seeds, rng_seed: int, *, n_videos: int = 6, with_patches: bool = False,
            p_det: float = 0.7) -> ProtocolResult:
    r = ProtocolResult(name, p, meta={"detector": "toy"})
    stems = [f"V_DRONE_{i:03d}" for i in (3, 10, 11, 56, 107, 200, 201, 230)[:n_videos]]
    for s in seeds:
        rng = np.random.default_rng([rng_seed, s])
        vids = [_random_video(np.random.default_rng([17, v]), 6) for v in range(n_videos)]  # the same ground truth
        dets = []
        for d_v, g_v in vids:
            # this condition's detector: keep each detection with probability p_det, rescore
            dd = []
            for d in d_v:
                keep = rng.random(len(d)) < p_det
                d = d[keep].copy()
                d[:, 4] = rng.random(len(d))
                dd.append(d)
            dets.append(dd)
        patches = []
        if with_patches:
            for v in range(n_videos):
                lab = (rng.random(30) < 0.1).astype(np.int8)
                patches.append(PatchVideoScores(stems[v], rng.normal(size=30) + 1.5 * lab, lab))
        r.add_seed(s, videos=match_videos(stems, dets, [g for _, g in vids], p), patches=patches, meta={"seed": s})
    return r


def test_result_json_round_trip(tmp_path: Path) -> None:
    p = proto()
    r = _result(p, "cnn", [0, 1, 2], 0, with_patches=True)
    text = json.dumps(r.to_json())
    back = ProtocolResult.from_json(json.loads(text))
    assert back.protocol == p and back.seed_ids == [0, 1, 2] and back.stems == r.stems and back.meta == r.meta
    for t in p.iou_thresholds:
        for b in [None, *p.size_buckets]:
            assert back.per_seed_ap(t, b) == pytest.approx(r.per_seed_ap(t, b), nan_ok=True)
    for s in r.seed_ids:
        for a, b in zip(r.seeds[s].videos, back.seeds[s].videos):
            for name in ("scores", "tp", "det_size", "match_size", "gt_size"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        for a, b in zip(r.seeds[s].patches, back.seeds[s].patches):
            np.testing.assert_array_equal(a.scores, b.scores)
            np.testing.assert_array_equal(a.labels, b.labels)
    path = r.save(tmp_path / "sub" / "r.json")
    assert ProtocolResult.load(path).to_json() == r.to_json()
    bad = json.loads(text)
    bad["fingerprint"] = "0" * 16
    with pytest.raises(ValueError, match="fingerprint"):
        ProtocolResult.from_json(bad)


def test_combine_seeds_run_separately() -> None:
    p = proto()
    parts = [_result(p, "cnn", [s], 0) for s in (0, 1, 2)]
    full = ProtocolResult.combine(parts)
    assert full.seed_ids == [0, 1, 2] and full.meets_min_seeds
    assert full.per_seed_ap() == pytest.approx({s: parts[s].per_seed_ap()[s] for s in range(3)})
    with pytest.raises(ValueError, match="already recorded"):
        ProtocolResult.combine([parts[0], parts[0]])
    with pytest.raises(ValueError, match="protocols"):
        ProtocolResult.combine([parts[0], _result(proto(min_training_seeds=2), "cnn", [5], 0)])
    with pytest.raises(ValueError, match="other videos"):
        full.add_seed(9, videos=_result(p, "x", [9], 0, n_videos=4).seeds[9].videos)
    with pytest.raises(ValueError, match="IoUs"):
        full.add_seed(9, videos=[match_video([np.zeros((0, 5))], [None], iou_thresholds=(0.5,), stem="V")])


def test_summary_and_report_table() -> None:
    p = proto(bootstrap={"resamples": 300, "seed": 0, "ci": 0.95})
    base = _result(p, "real", [0, 1, 2], 0, with_patches=True, p_det=0.5)
    better = _result(p, "ours", [0, 1, 2], 1, with_patches=True, p_det=0.95)
    few = _result(p, "two seeds", [0, 1], 2)
    results = {"real 100": base, "ours": better, "two seeds": few}
    sums = summarize_conditions(results, baseline="real 100")
    s = sums["ours"]
    assert s.ap[0.5].estimate == pytest.approx(better.mean_ap(0.5)) and s.ap[0.3].estimate == pytest.approx(better.mean_ap(0.3))
    assert s.ap[0.5].low <= s.ap[0.5].estimate <= s.ap[0.5].high
    assert s.paired is not None and s.paired.seeds == [0, 1, 2]
    assert s.paired.difference.estimate == pytest.approx(better.mean_ap() - base.mean_ap())
    assert sums["real 100"].paired is None
    assert sums["two seeds"].paired.seeds == [0, 1] and not sums["two seeds"].meets_min_seeds
    assert s.patch_ap is not None and 0.5 < s.patch_auc.estimate <= 1.0
    assert set(s.buckets) == {b.label for b in p.size_buckets}
    json.dumps({k: v.to_json() for k, v in sums.items()})  # JSON-ready
    table = report_table(results, baseline="real 100", summaries=sums)
    lines = table.splitlines()
    assert lines[0].startswith("| condition | seeds | AP@0.5 [95 % CI] | AP@0.3 [CI] | Δ AP@0.5 vs real 100 [CI] | videos improved |")
    assert "patch AP [CI]" in lines[0] and "patch ROC-AUC [CI]" in lines[0] and "AP@0.5 <24 px" in lines[0]
    assert len(lines[2].split("|")) == len(lines[0].split("|"))
    assert "(baseline)" in lines[2] and "2 ⚠" in lines[4] and "(on 2 common seeds)" in lines[4]
    assert "common seeds" not in lines[3]
    assert s.paired.difference.format(3, signed=True) in lines[3] and s.paired.wins.format() in lines[3]
    # the Δ's interval with the training seeds resampled too: same estimate, its own column, in the JSON
    cs = s.paired_seeds.difference
    assert s.paired_seeds.resampled == "seeds and videos" and cs.estimate == pytest.approx(s.paired.difference.estimate)
    assert "Δ CI, seeds resampled too" in lines[0] and f"[{cs.low:+.3f}, {cs.high:+.3f}]" in lines[3]
    assert s.to_json()["paired_seeds"]["resampled"] == "seeds and videos" and sums["real 100"].paired_seeds is None
    assert f"`{p.fingerprint()}`" in table and "⚠ fewer than the protocol's 3 training seeds" in table
    # same protocol required; baseline must exist
    with pytest.raises(ValueError, match="different protocols"):
        report_table({"a": base, "b": _result(proto(), "b", [0], 0)})
    with pytest.raises(ValueError, match="baseline"):
        report_table({"a": base}, baseline="nope")
    # no baseline: no Δ columns, recomputed summaries agree
    plain = report_table({"real 100": base})
    assert "Δ" not in plain.splitlines()[0] and sums["real 100"].ap[0.5].format() in plain


def test_report_marks_seeds_trained_on_another_machine() -> None:
    p = proto(bootstrap={"resamples": 50, "seed": 0, "ci": 0.95})
    here = {"cpu": "AMD EPYC", "cpu_capability": "AVX512", "torch": "2.14.1", "torch_threads": 1}
    there = dict(here, cpu_capability="AVX2")
    base, other = _result(p, "a", [0, 1, 2], 0), _result(p, "b", [0, 1, 2], 1)
    for s in (0, 1, 2):
        base.seeds[s].meta["trained_on"] = here
    # a field only one side records is not compared (seed 0: the same machine)
    for s, m in zip((0, 1, 2), (dict(here, cpu_family="25/17"), there, dict(there, extra="not in the baseline"))):
        other.seeds[s].meta["trained_on"] = m
    assert sorted(other.trained_elsewhere(base)) == [1, 2] and other.trained_elsewhere(other) == {}
    assert other.trained_elsewhere(base)[1] == (there, here)
    sums = summarize_conditions({"a": base, "b": other}, baseline="a")
    assert sums["b"].other_machine_seeds == [1, 2] and sums["b"].to_json()["other_machine_seeds"] == [1, 2]
    assert sums["b"].paired.difference.estimate == pytest.approx(other.mean_ap() - base.mean_ap())  # still computed
    table = report_table({"a": base, "b": other}, baseline="a", summaries=sums)
    row = table.splitlines()[3]
    assert row.startswith("| b |") and f"{sums['b'].paired.difference.format(3, signed=True)} †" in row
    assert "† seeds trained on another machine than the baseline's seeds of the same id (b: 1, 2" in table
    # no trained_on on a side (results stored before it was recorded): nothing claimed
    del base.seeds[1].meta["trained_on"], base.seeds[2].meta["trained_on"]
    assert other.trained_elsewhere(base) == {} and "†" not in report_table({"a": base, "b": other}, baseline="a")


def test_report_marks_incomparable_videos() -> None:
    p = proto(bootstrap={"resamples": 50, "seed": 0, "ci": 0.9})
    t = report_table({"a": _result(p, "a", [0, 1, 2], 0), "b": _result(p, "b", [0, 1, 2], 1, n_videos=4)}, baseline="a")
    assert "n/a (other videos)" in t and "AP@0.5 [90 % CI]" in t


# =========================================================================== scale check
@pytest.mark.parametrize("scale", [2.0, 0.75, 0.5, 1.3])
def test_scaled_box_still_encloses_the_drawn_rectangle(scale: float) -> None:
    frame = np.zeros((120, 160), np.uint8)
    x0, y0, x1, y1 = 37, 21, 83, 57  # pixels [x0, x1) x [y0, y1)
    frame[y0:y1, x0:x1] = 255
    out, boxes = scale_frame(frame, np.array([[x0, y0, x1, y1]], float), scale)
    assert out.shape == (round(120 * scale), round(160 * scale)) and out.dtype == np.uint8
    bx0, by0, bx1, by1 = boxes[0]
    ys, xs = np.nonzero(out > 127)  # the rectangle's pixels after resizing (more than half covered)
    # every rectangle pixel lies in the box (pixel centres u + 0.5), and the box is tight (within a pixel)
    assert xs.min() + 0.5 >= bx0 and xs.max() + 0.5 <= bx1 and ys.min() + 0.5 >= by0 and ys.max() + 0.5 <= by1
    assert abs(xs.min() - bx0) <= 1 and abs(xs.max() + 1 - bx1) <= 1 and abs(ys.min() - by0) <= 1 and abs(ys.max() + 1 - by1) <= 1
    # and nothing bright outside it
    mask = np.zeros_like(out, bool)
    mask[int(np.floor(by0)):int(np.ceil(by1)), int(np.floor(bx0)):int(np.ceil(bx1))] = True
    assert not (out[~mask] > 127).any()
    np.testing.assert_allclose(boxes[0], np.array([x0, y0, x1, y1]) * np.tile([out.shape[1] / 160, out.shape[0] / 120], 2))


def test_scale_interpolation_and_identity() -> None:
    import cv2

    rng = np.random.default_rng(0)
    f = rng.integers(0, 256, (64, 80), dtype=np.uint8)
    assert np.array_equal(scale_frame(f, None, 0.75)[0], cv2.resize(f, (60, 48), interpolation=cv2.INTER_AREA))
    assert np.array_equal(scale_frame(f, None, 2.0)[0], cv2.resize(f, (160, 128), interpolation=cv2.INTER_LINEAR))
    same, b = scale_frame(f, np.array([[1.0, 2.0, 3.0, 4.0]]), 1.0)
    assert np.array_equal(same, f) and same is not f and b.tolist() == [[1.0, 2.0, 3.0, 4.0]]
    with pytest.raises(ValueError, match="scale"):
        scale_frame(f, None, 0.0)


@dataclass
class _EvalSet:  # the fields of synthaug.evaluate.videos.EvalSet
    stems: list
    frames: list
    frame_indices: list
    boxes: list
    stride_k: int


def test_scale_eval_set() -> None:
    es = _EvalSet(["a"], [np.zeros((2, 40, 60), np.uint8)], [[0, 5]], [[np.array([[10.0, 4.0, 8.0, 6.0]]), None]], 5)
    out = scale_eval_set(es, 2.0)
    assert isinstance(out, _EvalSet) and out.frames[0].shape == (2, 80, 120) and out.stems == ["a"]
    np.testing.assert_allclose(out.boxes[0][0], [[20.0, 8.0, 16.0, 12.0]])  # XYWH in, XYWH out
    assert out.boxes[0][1] is None and es.frames[0].shape == (2, 40, 60)


# =========================================================================== patch protocol
@pytest.fixture(scope="module")
def tiny_videos(tmp_path_factory) -> Path:
    """Two generated videos with gaps in their numbering, one with unlabelled frames."""
    from synthaug.data.synthvideo import make_panning_video

    root = tmp_path_factory.mktemp("videos")
    make_panning_video(root, n_frames=9, size=(192, 144), seed=3, name="V_DRONE_003")
    make_panning_video(root, n_frames=7, size=(192, 144), seed=10, name="V_DRONE_010")
    lab = root / "labels" / "V_DRONE_010.json"
    doc = json.loads(lab.read_text())
    doc["boxes"][2] = None
    doc["boxes"][4] = None
    lab.write_text(json.dumps(doc))
    return root


def test_patch_eval_set(tiny_videos: Path) -> None:
    from synthaug.data.seedset import crop_geometry, crop_patch
    from synthaug.data.video import read_video_with_labels

    p = proto(test={"split": "test", "frame_stride": 2}, patch={"negatives_per_positive": 5, "seed": 0})
    stems = ["V_DRONE_010", "V_DRONE_003"]
    ps = patch_eval_set(tiny_videos / "videos", tiny_videos / "labels", "test", p, videos=stems)
    assert ps.stems == stems and ps.patches.shape[1:] == (40, 40) and ps.patches.dtype == np.uint8
    # V_DRONE_010: frames 0, 2, 4, 6 at stride 2, 2 and 4 unlabelled -> 2 positives; V_DRONE_003: frames 0..8 -> 5
    pos = ps.labels == 1
    assert [int((pos & (ps.video == v)).sum()) for v in range(2)] == [2, 5]
    assert ps.frame[pos & (ps.video == 0)].tolist() == [0, 6]
    assert ps.info["negatives"] + ps.info["negatives_missing"] == 5 * 7 and ps.info["negatives"] == int((~pos).sum())
    assert ps.info["negatives"] >= 30
    for v, stem in enumerate(stems):
        frames, labels, _ = read_video_with_labels(tiny_videos / "videos" / f"{stem}.mp4", tiny_videos / "labels" / f"{stem}.json")
        for i in np.nonzero(ps.video == v)[0]:
            f = int(ps.frame[i])
            box = labels.boxes[f]
            if ps.labels[i]:  # cropped exactly as seeds are
                want, crop = crop_patch(frames[f], box=box, patch_size=40, object_fraction=0.7)
                assert np.array_equal(ps.patches[i], want)
                np.testing.assert_allclose(ps.crop[i], crop_geometry(box, patch_size=40, object_fraction=0.7))
                side = float(ps.crop[i][2])
            else:  # same frame, the positive's crop side, inside the frame, no overlap with the object
                cx, cy, s = (float(x) for x in ps.crop[i])
                assert s == pytest.approx(side)
                assert s / 2 <= cx <= frames.shape[2] - s / 2 and s / 2 <= cy <= frames.shape[1] - s / 2
                x, y, w, h = box
                assert cx + s / 2 <= x or cx - s / 2 >= x + w or cy + s / 2 <= y or cy - s / 2 >= y + h
                want, _ = crop_patch(frames[f], crop=ps.crop[i], patch_size=40)
                assert np.array_equal(ps.patches[i], want)
    # deterministic, and a video's patches do not depend on the other videos
    again = patch_eval_set(tiny_videos / "videos", tiny_videos / "labels", "test", p, videos=stems)
    assert np.array_equal(again.patches, ps.patches) and np.array_equal(again.crop, ps.crop)
    alone = patch_eval_set(tiny_videos / "videos", tiny_videos / "labels", "test", p, videos=["V_DRONE_003"])
    np.testing.assert_array_equal(alone.crop, ps.crop[ps.video == 1])
    other = patch_eval_set(tiny_videos / "videos", tiny_videos / "labels", "test",
                           proto(test={"split": "test", "frame_stride": 2}, patch={"negatives_per_positive": 5, "seed": 1}),
                           videos=stems)
    assert not np.array_equal(other.crop, ps.crop)
    with pytest.raises(ValueError, match="no video file"):
        patch_eval_set(tiny_videos / "videos", tiny_videos / "labels", "test", p, videos=["V_DRONE_004"])


class _DarkDetector:
    """Scores a patch by how dark its centre is (the generated quadcopter is dark on the sky)."""

    window = 40

    def score_patches(self, patches):
        return 1.0 - patches[:, 0, 14:26, 14:26].mean(dim=(1, 2))


def test_score_and_patch_metrics(tiny_videos: Path) -> None:
    from scipy.stats import mannwhitneyu

    p = proto(test={"split": "test", "frame_stride": 1}, patch={"negatives_per_positive": 8, "seed": 0})
    ps = patch_eval_set(tiny_videos / "videos", tiny_videos / "labels", "test", p, videos=["V_DRONE_003", "V_DRONE_010"])
    per_video = score_patch_set(_DarkDetector(), ps, batch_size=7)
    assert [v.stem for v in per_video] == ps.stems
    scores = np.concatenate([v.scores for v in per_video])
    labels = np.concatenate([v.labels for v in per_video])
    assert np.array_equal(labels, np.concatenate([ps.labels[ps.video == i] for i in range(2)]))
    vids = np.concatenate([[v.stem] * v.scores.size for v in per_video])
    m = patch_metrics(scores, labels, vids, bootstrap=BootstrapSpec(200, 0, 0.95))
    u = mannwhitneyu(scores[labels == 1], scores[labels == 0]).statistic
    assert m.roc_auc.estimate == pytest.approx(u / (m.n_positive * m.n_negative), abs=1e-12)
    assert m.n_positive == 14 and m.n_videos == 2 and m.roc_auc.estimate > 0.75 and m.ap.estimate > 2 * 14 / 126
    assert m.ap.low <= m.ap.estimate <= m.ap.high and m.roc_auc.low <= m.roc_auc.high
    # AP is synthaug.evaluate.ap's on the ranking
    from synthaug.evaluate.ap import average_precision, precision_recall

    o = np.argsort(-scores, kind="stable")
    pr, rc, _ = precision_recall(scores[o], labels[o].astype(bool), int(labels.sum()))
    assert m.ap.estimate == pytest.approx(average_precision(pr, rc))
    # several seeds: the mean; in a ProtocolResult the same numbers come out of the table
    m2 = patch_metrics({0: scores, 1: -scores}, labels, vids, bootstrap=BootstrapSpec(50, 0, 0.95))
    assert m2.roc_auc.estimate == pytest.approx((m.roc_auc.estimate + (1 - m.roc_auc.estimate)) / 2)
    r = ProtocolResult("dark", p)
    r.add_seed(0, patches=per_video)
    sums = summarize_conditions({"dark": r})
    assert sums["dark"].patch_auc.estimate == pytest.approx(m.roc_auc.estimate)
    assert "patch ROC-AUC" in report_table({"dark": r})
    no_ci = patch_metrics(scores, labels)
    assert no_ci.ap.estimate == pytest.approx(m.ap.estimate) and np.isnan(no_ci.ap.low)
    with pytest.raises(ValueError, match="window"):
        score_patch_set(type("W", (), {"window": 32, "score_patches": None})(), ps)


# =========================================================================== unlabelled frames (protocol v2)
def test_committed_v2_differs_from_v1_only_in_skipping_unlabelled_frames() -> None:
    v1 = load_protocol(REPO / "configs" / "protocol" / "halmstad_v1.json")
    v2 = load_protocol(REPO / "configs" / "protocol" / "halmstad_v2.json")
    assert (v1.test.unlabelled_frames, v1.val.unlabelled_frames) == ("score", "score")
    assert (v2.name, v2.version, v2.test.unlabelled_frames, v2.val.unlabelled_frames) == ("halmstad_v2", 2, "skip", "skip")
    assert v2.fingerprint() != v1.fingerprint()
    d1, d2 = v1.to_dict(), v2.to_dict()
    for d in (d1, d2):
        d.pop("description"), d.pop("name"), d.pop("version")
        d["test"].pop("unlabelled_frames", None), d["val"].pop("unlabelled_frames", None)
    assert d1 == d2
    # the field is absent from a v1 protocol's canonical form: v1's fingerprint did not move when it was added
    assert "unlabelled_frames" not in v1.to_dict()["test"]
    assert proto(test={"split": "test", "frame_stride": 5, "unlabelled_frames": "score"}).fingerprint() == proto().fingerprint()
    assert Protocol.from_dict(v2.to_dict()) == v2
    with pytest.raises(ProtocolError, match="test.unlabelled_frames"):
        proto(test={"split": "test", "frame_stride": 5, "unlabelled_frames": "ignore"})


def test_load_eval_set_skips_frames_without_a_labelled_box(tiny_videos: Path) -> None:
    from synthaug.data.video import read_video_with_labels
    from synthaug.evaluate.matching import match_videos
    from synthaug.evaluate.videos import load_eval_set

    stems = ["V_DRONE_010", "V_DRONE_003"]
    every = load_eval_set(stems, tiny_videos / "videos", tiny_videos / "labels", stride_k=2)
    kept = load_eval_set(stems, tiny_videos / "videos", tiny_videos / "labels", stride_k=2, skip_unlabelled=True)
    # V_DRONE_010: frames 0, 2, 4, 6 at stride 2, 2 and 4 null -> 0 and 6 kept; V_DRONE_003: all labelled
    assert every.frame_indices[0] == [0, 2, 4, 6] and kept.frame_indices[0] == [0, 6]
    assert kept.frame_indices[1] == every.frame_indices[1]
    frames, labels, _ = read_video_with_labels(tiny_videos / "videos" / "V_DRONE_010.mp4",
                                               tiny_videos / "labels" / "V_DRONE_010.json")
    for j, f in enumerate(kept.frame_indices[0]):  # the frames and boxes kept are those of the kept indices
        assert np.array_equal(kept.frames[0][j], frames[f])
        np.testing.assert_allclose(np.asarray(kept.boxes[0][j]).reshape(-1, 4), np.asarray(labels.boxes[f]).reshape(-1, 4))
    assert kept.n_objects == every.n_objects and kept.n_frames == every.n_frames - 2
    # a confident detection on a skipped frame is no false positive any more: one box per frame, scored
    p = proto(test={"split": "test", "frame_stride": 2})

    def dets(es):
        return [[np.array([[0.0, 0.0, 8.0, 8.0, 1.0]]) for _ in fr] for fr in es.frames]

    fp_every = sum(int((~m.tp[0]).sum()) for m in match_videos(every.stems, dets(every), every.boxes, p))
    fp_kept = sum(int((~m.tp[0]).sum()) for m in match_videos(kept.stems, dets(kept), kept.boxes, p))
    assert fp_every - fp_kept == 2
    # a video whose scored frames hold no box at all is left out, with a warning naming it
    lab = tiny_videos / "labels" / "V_DRONE_003.json"
    doc = json.loads(lab.read_text())
    empty = tiny_videos / "labels_empty"
    empty.mkdir(exist_ok=True)
    (empty / "V_DRONE_003.json").write_text(json.dumps(dict(doc, boxes=[None] * len(doc["boxes"]))))
    (empty / "V_DRONE_010.json").write_text((tiny_videos / "labels" / "V_DRONE_010.json").read_text())
    with pytest.warns(UserWarning, match="V_DRONE_003"):
        es = load_eval_set(stems, tiny_videos / "videos", empty, stride_k=2, skip_unlabelled=True)
    assert es.stems == ["V_DRONE_010"]
