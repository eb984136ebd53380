"""The CNN box regressor (synthaug.detectors.box_cnn): what it exists for — jittered detector boxes come closer to
the annotators' box on held-out frames, measured with torchvision's box_iou (on real drones it also beats the
ridge map: see the box_cnn module docstring; on these clean rectangles both do) — plus the detector file round trip, reproducibility and clear errors."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torchvision.ops import box_convert, box_iou

from synthaug.detectors.base import load_detector, save_detector
from synthaug.detectors.box_cnn import CNNBoxRegressor, EnsembleBoxRegressor, regressor_from_state_dict
from synthaug.detectors.boxes import BoxRegressor, jitter_boxes
from synthaug.detectors.frames import MiningFrame
from synthaug.detectors.training import TrainOptions


def _frames(n: int, seed: int) -> list[MiningFrame]:
    """Dark rectangles of random size (8-60 px) and aspect on a bright textured sky: the annotators' box is the
    rectangle (sizes span a factor 7, as objects of one class do over a scale check)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        img = np.clip(170 + 25 * rng.standard_normal((160, 200)).cumsum(1) / 30, 0, 255)
        side = np.exp(rng.uniform(np.log(8), np.log(60)))
        w, h = side * rng.uniform(0.8, 1.3), side * rng.uniform(0.6, 1.0)
        x, y = rng.uniform(10, 200 - w - 10), rng.uniform(10, 160 - h - 10)
        img[int(round(y)):int(round(y + h)), int(round(x)):int(round(x + w))] = 40
        box = np.array([[round(x), round(y), round(x + w) - round(x), round(y + h) - round(y)]], float)
        out.append(MiningFrame(img.astype(np.uint8), box, f"V_{i % 6}", i))
    return out


def _mean_iou(refine, frames) -> tuple[float, float]:
    gen = torch.Generator().manual_seed(7)
    before, after = [], []
    for f in frames:
        g = box_convert(torch.as_tensor(f.boxes, dtype=torch.float32), "xywh", "xyxy")
        p, _ = jitter_boxes(g, 10, aspect=1.3, generator=gen)
        image = torch.as_tensor(f.image).float() / 255
        before.append(box_iou(p, g)[:, 0])
        after.append(box_iou(refine(image, p), g)[:, 0])
    return float(torch.cat(before).mean()), float(torch.cat(after).mean())


@pytest.fixture(scope="module")
def fitted() -> CNNBoxRegressor:
    torch.set_num_threads(1)
    return CNNBoxRegressor.fit(_frames(80, 0), aspect=1.3, jitters=24, seed=0, epochs=6)


def test_cnn_regressor_moves_jittered_boxes_towards_the_labelled_box(fitted):
    meta = fitted.meta
    assert meta["videos"] == 6 and len(meta["held_out_videos"]) == 1 and meta["samples"] > 1000
    assert min(meta["held_out_mse"]) < 0.5 * meta["held_out_mse_no_regression"], meta
    assert meta["held_out_mse"][meta["epoch_kept"]] == min(meta["held_out_mse"])
    held_out = _frames(30, 1)
    before, after = _mean_iou(fitted.refine, held_out)
    assert after > before + 0.15, (before, after)


def test_fit_is_reproducible_and_the_state_round_trips_through_the_detector_file(fitted, tmp_path):
    again = CNNBoxRegressor.fit(_frames(80, 0), aspect=1.3, jitters=24, seed=0, epochs=6)
    for k, v in fitted.net.state_dict().items():
        assert torch.equal(v, again.net.state_dict()[k]), k
    from synthaug.detectors.toy import toy_patches
    from synthaug.detectors.training import train_detector

    pos, neg = toy_patches(40, 80, seed=0)
    det = train_detector("hog", pos, neg, seed=0, options=TrainOptions(hog_components=1, hog_mining_rounds=0))
    det.box_regressor = fitted
    back = load_detector(save_detector(det, tmp_path / "d.pt"))
    assert isinstance(back.box_regressor, CNNBoxRegressor)
    image, boxes = torch.rand(1, 1, 80, 90, generator=torch.Generator().manual_seed(0)), torch.tensor([[10., 12., 40., 35.]])
    assert torch.equal(back.box_regressor.refine(image, boxes), fitted.refine(image, boxes))
    assert back.box_regressor.meta["epoch_kept"] == fitted.meta["epoch_kept"]


def test_regressor_states_dispatch_by_model_and_bad_input_is_a_clear_error(fitted):
    assert isinstance(regressor_from_state_dict(BoxRegressor.identity().state_dict()), BoxRegressor)
    legacy = {k: v for k, v in BoxRegressor.identity().state_dict().items() if k != "model"}  # files before box_model
    assert isinstance(regressor_from_state_dict(legacy), BoxRegressor)
    state = fitted.state_dict()
    with pytest.raises(ValueError, match="model 'svm'"):
        regressor_from_state_dict({**state, "model": "svm"})
    with pytest.raises(ValueError, match="malformed"):
        regressor_from_state_dict({**state, "net": {"0.weight": torch.zeros(3)}})
    with pytest.raises(ValueError, match="missing"):
        CNNBoxRegressor.from_state_dict({k: v for k, v in state.items() if k != "mean_y"})
    with pytest.raises(ValueError, match="no labelled box"):
        CNNBoxRegressor.fit([MiningFrame(np.zeros((50, 50), np.uint8), None, "v", 0)], aspect=1.0)
    with pytest.raises(ValueError, match="epochs"):
        CNNBoxRegressor.fit(_frames(4, 0), aspect=1.0, epochs=0)
    with pytest.raises(ValueError, match="box_model"):
        TrainOptions(box_model="svm")
    assert CNNBoxRegressor.untrained().refine(torch.rand(8, 8), torch.zeros(0, 4)).shape == (0, 4)


def test_ensemble_is_the_mean_of_its_parts_deltas_and_round_trips(fitted):
    ridge = BoxRegressor.fit(_frames(40, 0), aspect=1.3, jitters=8, seed=0)
    ens = EnsembleBoxRegressor([ridge, fitted])
    image = torch.as_tensor(_frames(1, 5)[0].image).float()[None, None] / 255
    boxes = torch.tensor([[20., 30., 60., 60.], [100., 40., 130., 70.]])
    torch.testing.assert_close(ens.predict(image, boxes), (ridge.predict(image, boxes) + fitted.predict(image, boxes)) / 2)
    back = regressor_from_state_dict(ens.state_dict())
    assert isinstance(back, EnsembleBoxRegressor) and [type(p) for p in back.parts] == [BoxRegressor, CNNBoxRegressor]
    torch.testing.assert_close(back.refine(image, boxes), ens.refine(image, boxes))
    with pytest.raises(ValueError, match="parts"):
        regressor_from_state_dict({"model": "ensemble", "parts": []})
    with pytest.raises(ValueError, match="at least one"):
        EnsembleBoxRegressor([])
