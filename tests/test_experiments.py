"""Tests of the experiments' parts on generated data: the perturbation baseline (effects.perturb), evaluation
on videos (evaluate.videos), detector training, the runner and its cell cache (evaluate.context), reports."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from synthaug.detectors.base import PatchDetector
from synthaug.detectors.training import TrainOptions, train_detector
from synthaug.evaluate.context import ExperimentContext
from synthaug.effects.perturb import perturb_patches
from synthaug.evaluate.reporting import _plot, _write_report
from synthaug.evaluate.videos import EvalSet, detect_on_eval_set, evaluate_on_videos, load_eval_set

class DarknessDetector(PatchDetector):
    """Scores a window by how dark it is (1 - mean intensity): an oracle for dark squares on grey."""

    kind = "darkness_test"

    def __init__(self) -> None:
        self.window, self.stride = 40, 4

    def score_patches(self, patches: torch.Tensor) -> torch.Tensor:
        return 1 - patches.mean((1, 2, 3))

    def score_map(self, image: torch.Tensor) -> torch.Tensor:
        return 1 - F.avg_pool2d(image, self.window, self.stride)[0, 0]

    def state_dict(self) -> dict[str, Any]:
        return {}

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> "DarknessDetector":
        return cls()


def _frame(squares: list[tuple[int, int, int]]) -> np.ndarray:
    f = np.full((120, 160), 200, np.uint8)
    for x, y, v in squares:
        f[y:y + 40, x:x + 40] = v
    return f


# ----------------------------------------------------------------- perturbation baseline
def test_perturb_shapes_range_determinism_no_inplace() -> None:
    x = torch.rand(5, 1, 40, 40, generator=torch.Generator().manual_seed(0))
    before = x.clone()
    a = perturb_patches(x, 3, generator=torch.Generator().manual_seed(7))
    b = perturb_patches(x, 3, generator=torch.Generator().manual_seed(7))
    c = perturb_patches(x, 3, generator=torch.Generator().manual_seed(8))
    assert a.shape == (15, 1, 40, 40)
    assert torch.equal(x, before)
    assert torch.equal(a, b)
    assert not torch.equal(a, c)
    assert float(a.min()) >= 0 and float(a.max()) <= 1
    assert perturb_patches(x, 0, generator=torch.Generator()).shape == (0, 1, 40, 40)


def test_perturb_mirror_only_is_identity_or_flip() -> None:
    """With every range at 0, each copy is its source patch or its mirror image, exactly (up to float rounding)."""
    x = torch.rand(6, 1, 40, 40, generator=torch.Generator().manual_seed(1))
    y = perturb_patches(x, 4, generator=torch.Generator().manual_seed(2), max_rotation_deg=0, max_translation=0,
                        max_blur_sigma=0, max_noise_sigma=0)
    src = x.repeat(4, 1, 1, 1)
    same = (y - src).abs().amax((1, 2, 3)) < 1e-5
    flipped = (y - src.flip(-1)).abs().amax((1, 2, 3)) < 1e-5
    assert bool((same | flipped).all())
    assert 0 < int(flipped.sum()) < len(y)  # both happen


def test_perturb_translation_matches_integer_shift() -> None:
    """A pure translation of a whole number of pixels equals numpy's shift of the patch (border replicated)."""
    x = torch.rand(1, 1, 40, 40, generator=torch.Generator().manual_seed(3))
    g = torch.Generator().manual_seed(0)
    # draw exactly as perturb_patches does to learn the shift, then check against numpy
    y = perturb_patches(x, 1, generator=g, max_rotation_deg=0, max_translation=0.1, mirror=False, max_blur_sigma=0,
                        max_noise_sigma=0)
    g2 = torch.Generator().manual_seed(0)
    torch.rand(1, generator=g2)  # angle
    shift = ((torch.rand(1, 2, generator=g2) * 2 - 1) * 0.2)[0]  # normalised units, span 2 = 40 px
    dx, dy = (shift * 20).tolist()  # output(u) = input(u + d)
    # compare in the interior, away from the replicated border, with a bilinear numpy reference
    from scipy.ndimage import map_coordinates

    yy, xx = np.mgrid[0:40, 0:40].astype(np.float64)
    ref = map_coordinates(x[0, 0].double().numpy(), [yy + dy, xx + dx], order=1, mode="nearest")
    np.testing.assert_allclose(y[0, 0].numpy()[6:-6, 6:-6], ref[6:-6, 6:-6], atol=1e-5)


def test_perturb_blur_lowers_gradient_energy() -> None:
    x = (torch.rand(8, 1, 40, 40, generator=torch.Generator().manual_seed(4)) > 0.5).float()
    y = perturb_patches(x, 1, generator=torch.Generator().manual_seed(5), max_rotation_deg=0, max_translation=0,
                        mirror=False, max_blur_sigma=1.5, max_noise_sigma=0)
    grad = lambda t: (t[..., 1:] - t[..., :-1]).abs().mean((1, 2, 3))  # noqa: E731
    assert bool((grad(y) <= grad(x) + 1e-6).all())
    with pytest.raises(ValueError, match="copies"):
        perturb_patches(x, -1, generator=torch.Generator())


# ----------------------------------------------------------------- evaluation
def test_evaluate_on_videos_hand_computed_ap() -> None:
    """Oracle detector on grey frames with dark squares; AP checked against a hand computation."""
    # frame 0: object at (40, 40); frame 1: object at (80, 40) and an unlabelled darker distractor at (0, 80)
    f0 = _frame([(40, 40, 20)])
    f1 = _frame([(80, 40, 60), (0, 80, 0)])
    es = EvalSet(stems=["v"], frames=[np.stack([f0, f1])], frame_indices=[[0, 1]],
                 boxes=[[np.array([[40.0, 40, 40, 40]]), np.array([[80.0, 40, 40, 40]])]], stride_k=1)
    res = evaluate_on_videos(DarknessDetector(), es, scales=(1.0,), max_detections=1)
    # one detection per frame; by score: distractor (frame 1, score 1.0) = FP, object in frame 0 (0.92) = TP
    # precision/recall steps: (p=0, r=0), (p=1/2, r=1/2) -> AP = 0.5 * 0.5 = 0.25
    assert res.ap == pytest.approx(0.25)
    assert res.n_frames == 2 and res.n_objects == 2
    res2 = evaluate_on_videos(DarknessDetector(), es, scales=(1.0,), max_detections=2)
    # adds the frame-1 object (score 0.765) as 3rd: (1/2, 1/2), (2/3, 1) -> AP = 0.25 + 0.5 * 2/3
    assert res2.ap == pytest.approx(0.25 + 0.5 * 2 / 3)
    assert res2.per_video["v"] == pytest.approx(res2.ap)


def test_detect_on_eval_set_per_video_per_frame() -> None:
    """Detections per video and per frame, (K, 5) XYWH+score; evaluate_on_videos scores exactly these."""
    from synthaug.evaluate.ap import evaluate_detections

    f0, f1, f2 = _frame([(40, 40, 20)]), _frame([(80, 40, 60), (0, 80, 0)]), _frame([])
    es = EvalSet(stems=["a", "b"], frames=[np.stack([f0, f1]), f2[None]], frame_indices=[[0, 1], [0]],
                 boxes=[[np.array([[40.0, 40, 40, 40]]), np.array([[80.0, 40, 40, 40]])], [None]], stride_k=1)
    dets = detect_on_eval_set(DarknessDetector(), es, scales=(1.0,), max_detections=2)
    assert [len(v) for v in dets] == [2, 1]
    for d in (x for v in dets for x in v):
        assert d.dtype == np.float64 and d.ndim == 2 and d.shape[1] == 5 and d.shape[0] <= 2
    top = dets[0][0][np.argmax(dets[0][0][:, 4])]
    np.testing.assert_allclose(top[:4], [40, 40, 40, 40])
    assert top[4] == pytest.approx(1 - 20 / 255, abs=1e-5)
    one = detect_on_eval_set(DarknessDetector(), es, scales=(1.0,), max_detections=1)
    assert all(len(d) == 1 for v in one for d in v)
    res = evaluate_on_videos(DarknessDetector(), es, scales=(1.0,), max_detections=2)
    flat = [d for v in dets for d in v]
    assert res.ap == pytest.approx(float(evaluate_detections(flat, [b for bs in es.boxes for b in bs], 0.5).ap))


def test_load_eval_set_matches_direct_decode(tmp_path: Path) -> None:
    import cv2

    from synthaug.data.synthvideo import make_panning_video

    v = make_panning_video(tmp_path, n_frames=8, size=(160, 128), seed=3, name="V_T_001")
    es = load_eval_set(["V_T_001"], tmp_path / "videos", tmp_path / "labels", stride_k=3)
    assert es.frame_indices == [[0, 3, 6]]
    labels = json.loads(v.labels_path.read_text())["boxes"]
    for j, i in enumerate([0, 3, 6]):
        np.testing.assert_allclose(es.boxes[0][j][0], labels[i])
    cap = cv2.VideoCapture(str(v.video_path))
    decoded = []
    for _ in range(8):
        ok, fr = cap.read()
        decoded.append(cv2.cvtColor(fr, cv2.COLOR_BGR2GRAY))
    cap.release()
    for j, i in enumerate([0, 3, 6]):
        np.testing.assert_array_equal(es.frames[0][j], decoded[i])
    with pytest.raises(ValueError, match="stride_k"):
        load_eval_set(["V_T_001"], tmp_path / "videos", tmp_path / "labels", stride_k=0)
    with pytest.raises(ValueError, match="V_MISSING"):
        load_eval_set(["V_MISSING"], tmp_path / "videos", tmp_path / "labels")


# ----------------------------------------------------------------- training
SMALL = TrainOptions(hog_components=2, hog_mining_rounds=0, ada_rounds=15, ada_candidates=300, cnn_epochs=3)


@pytest.mark.parametrize("kind", ["hog", "adaboost", "cnn"])
def test_train_detector_separates_toy_patches(kind: str) -> None:
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(120, 240, seed=0)
    test_pos, test_neg = toy_patches(60, 60, seed=1)
    det = train_detector(kind, pos, neg, 0, box_in_window=(5, 5, 30, 30), options=SMALL)
    assert det.box_in_window == (5.0, 5.0, 30.0, 30.0)
    s_pos, s_neg = det.score_patches(test_pos), det.score_patches(test_neg)
    # ranking quality (AUC) on held-out toy patches, computed directly
    auc = float((s_pos[:, None] > s_neg[None, :]).float().mean())
    assert auc > 0.85, auc


def test_train_detector_deterministic_and_bad_inputs() -> None:
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(40, 80, seed=0)
    a = train_detector("cnn", pos, neg, 3, options=SMALL).score_patches(neg)
    b = train_detector("cnn", pos, neg, 3, options=SMALL).score_patches(neg)
    assert torch.equal(a, b)
    with pytest.raises(ValueError, match="svm"):
        train_detector("svm", pos, neg)
    with pytest.raises(ValueError, match="positives"):
        train_detector("cnn", pos[:0], neg)


# ----------------------------------------------------------------- cells, reports
def _video_ctx(tmp_path: Path) -> ExperimentContext:
    from synthaug.data.synthvideo import make_panning_video

    for i, stem in enumerate(["V_DRONE_001", "V_DRONE_002"]):
        make_panning_video(tmp_path, n_frames=6, size=(160, 128), seed=i, name=stem)
    split = {"format": "synthaug.video_split", "version": 1, "classes": {"V_DRONE_001": "drone", "V_DRONE_002": "drone"},
             "train": [], "val": ["V_DRONE_001"], "test": ["V_DRONE_002"], "hard_negatives": {}}
    (tmp_path / "split.json").write_text(json.dumps(split))
    return ExperimentContext(out_dir=tmp_path / "out", videos_dir=tmp_path / "videos", labels_dir=tmp_path / "labels",
                             split_file=tmp_path / "split.json", stride_k=2, val_stride_k=3, scales=(1.0,),
                             options=SMALL, log=lambda m: None)


def test_cell_is_cached_and_resumes(tmp_path: Path) -> None:
    from synthaug.detectors.toy import toy_patches

    ctx = _video_ctx(tmp_path)
    calls = []

    def build() -> dict[str, Any]:
        calls.append(1)
        pos, neg = toy_patches(40, 80, seed=0)
        return {"positives": pos, "negatives": neg}

    first = ctx.cell("toy", "cnn", build, splits=("test",))
    assert ctx.eval_set("test").frame_indices == [[0, 2, 4]]
    assert 0.0 <= first["test"]["ap"] <= 1.0 and first["test"]["n_frames"] == 3
    again = ctx.cell("toy", "cnn", build, splits=("test",))
    assert len(calls) == 1 and again["test"] == first["test"]
    # a new context on the same folder reads the cache: asking for val trains once more, test is kept
    ctx2 = _video_ctx(tmp_path)
    both = ctx2.cell("toy", "cnn", build, splits=("val", "test"))
    assert len(calls) == 2 and both["test"] == first["test"] and both["val"]["n_frames"] == 2
    cells = json.loads((tmp_path / "out" / "cells.json").read_text())
    assert first["test"] in _leaves(cells), "the test result is not in cells.json"
    # same seed, same training set: a context without the cache retrains and gives the same test AP
    (tmp_path / "fresh").mkdir()
    third = _video_ctx(tmp_path / "fresh").cell("toy", "cnn", build, splits=("test",))
    assert len(calls) == 3 and third["test"]["ap"] == first["test"]["ap"]


def _leaves(doc: Any) -> list[dict[str, Any]]:
    """Every dict nested in ``doc`` (the cell entries of a cells.json, whatever its layout)."""
    out = []
    if isinstance(doc, dict):
        out.append(doc)
        for v in doc.values():
            out += _leaves(v)
    elif isinstance(doc, list):
        for v in doc:
            out += _leaves(v)
    return out


def test_report_writes_table_plot_json(tmp_path: Path) -> None:
    ctx = ExperimentContext(out_dir=tmp_path, log=lambda m: None)
    _write_report(ctx, "t", "title", ["a", "b"], [["x", 0.5], ["y", None]], {"x": 0.5})
    md = (tmp_path / "t.md").read_text()
    assert "| x | 0.500 |" in md and "| y | – |" in md
    assert json.loads((tmp_path / "t.json").read_text()) == {"x": 0.5}
    _plot(tmp_path / "p.png", "line", {"s": {0: 0.1, 5: 0.3}}, title="t", xlabel="r", logx=True, marks={"s": 5})
    _plot(tmp_path / "q.png", "bar", {"d": {"a": 0.2, "b": None}}, title="t", xlabel="d")
    assert (tmp_path / "p.png").stat().st_size > 1000 and (tmp_path / "q.png").stat().st_size > 1000


def test_moved_names_still_importable_from_experiments() -> None:
    """experiments.py re-exports every name that moved to its own module (the same objects)."""
    import synthaug.detectors.training as training
    import synthaug.detectors.training_sets as training_sets
    import synthaug.evaluate.context as context
    import synthaug.evaluate.experiments as ex
    import synthaug.effects.perturb as perturb
    import synthaug.evaluate.reporting as reporting
    import synthaug.evaluate.videos as videos

    homes = {videos: ["EvalSet", "EvalResult", "load_eval_set", "evaluate_on_videos", "detect_on_eval_set"],
             perturb: ["perturb_patches"], context: ["ExperimentContext"],
             reporting: ["_fmt", "_stem", "_write_report", "_plot", "_ap"],
             training: ["DETECTORS", "TrainOptions", "train_detector"],
             training_sets: ["real_positives", "synthetic_positives", "frames_training_set", "negative_pool",
                             "mining_frames", "perturbed_positives"]}
    for module, names in homes.items():
        for name in names:
            assert getattr(ex, name) is getattr(module, name), name
    assert all(hasattr(ex, name) for name in ex.__all__)
    assert list(ex.EXPERIMENTS) == ["baselines", "fig11_ratio", "table1_perturbation", "fig10_fitted_vs_uniform",
                                    "fig9_effects_off", "fig12_seeds", "table2_detector_distance"]
