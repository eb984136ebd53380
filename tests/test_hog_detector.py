"""The HOG mixture detector: training on a generated problem, dense scoring, detection, checkpoints."""

from __future__ import annotations

import math

import pytest
import torch
import torch.nn.functional as F
from torchvision.ops import box_convert, box_iou

from synthaug.detectors.base import (
    PatchDetector,
    box_in_window_from_boxes,
    get_detector_class,
    list_detectors,
    load_detector,
    register_detector,
    save_detector,
)
from synthaug.detectors.hog import DEFAULT_HOG, dense_block_map
from synthaug.detectors.hog_dpm import HOGDetector, kmeans, kmeans_inertia, train_linear_svm
from synthaug.detectors.sliding import detect_multiscale


def _background(h: int, w: int, g: torch.Generator) -> torch.Tensor:
    yy, xx = torch.meshgrid(torch.arange(float(h)), torch.arange(float(w)), indexing="ij")
    img = 0.55 + 0.15 * torch.rand((), generator=g) + 0.1 * torch.sin(xx / 9 + 6 * torch.rand((), generator=g)) * torch.cos(yy / 13)
    return (img + 0.02 * torch.randn(h, w, generator=g)).clamp(0, 1)


def _paint_object(img: torch.Tensor, cx: float, cy: float, size: float, kind: int) -> None:
    """A dark cross-shaped 'drone' (kind 0) or a wide bar 'airplane' (kind 1), longest side = size."""
    h, w = img.shape
    yy, xx = torch.meshgrid(torch.arange(float(h)), torch.arange(float(w)), indexing="ij")
    u, v = (xx - cx) / (size / 2), (yy - cy) / (size / 2)
    if kind == 0:
        mask = ((u.abs() < 1) & (v.abs() < 0.2)) | ((v.abs() < 1) & (u.abs() < 0.2)) | (u**2 + v**2 < 0.16)
    else:
        mask = ((u.abs() < 1) & (v.abs() < 0.25)) | ((u.abs() < 0.2) & (v.abs() < 0.7))
    img[mask] = 0.12


def _problem(seed: int = 0, n_pos: int = 80, n_neg: int = 300) -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    pos = []
    for i in range(n_pos):
        patch = _background(40, 40, g)
        jitter = (torch.rand(2, generator=g) - 0.5) * 2
        _paint_object(patch, 19.5 + float(jitter[0]), 19.5 + float(jitter[1]), 28 * (0.9 + 0.2 * float(torch.rand((), generator=g))), i % 2)
        pos.append(patch)
    neg = []
    for _ in range(n_neg // 10):
        frame = _background(120, 120, g)
        for _ in range(10):
            y, x = torch.randint(0, 81, (2,), generator=g).tolist()
            neg.append(frame[y : y + 40, x : x + 40])
    return torch.stack(pos)[:, None], torch.stack(neg)[:, None]


@pytest.fixture(scope="module")
def trained() -> HOGDetector:
    pos, neg = _problem()
    bg = [_background(100, 140, torch.Generator().manual_seed(100 + i)) for i in range(2)]
    return HOGDetector.fit(pos, neg, background_images=bg, components=3, mining_rounds=2, generator=torch.Generator().manual_seed(1))


def test_trained_detector_separates_held_out_patches(trained: HOGDetector) -> None:
    pos, neg = _problem(seed=7, n_pos=40, n_neg=200)
    s_pos, s_neg = trained.score_patches(pos), trained.score_patches(neg)
    assert s_pos.shape == (40,) and s_neg.shape == (200,)
    assert (s_pos > 0).float().mean() > 0.9
    assert (s_neg < 0).float().mean() > 0.95
    # ranking quality: AUC from all pairs
    auc = (s_pos[:, None] > s_neg[None, :]).float().mean()
    assert auc > 0.98


def test_training_is_deterministic_given_generator() -> None:
    pos, neg = _problem(seed=3, n_pos=20, n_neg=60)
    a = HOGDetector.fit(pos, neg, components=2, mining_rounds=1, generator=torch.Generator().manual_seed(5))
    b = HOGDetector.fit(pos, neg, components=2, mining_rounds=1, generator=torch.Generator().manual_seed(5))
    torch.testing.assert_close(a.weights, b.weights)


def test_score_map_equals_convolution_reference(trained: HOGDetector) -> None:
    image = _background(90, 110, torch.Generator().manual_seed(4))
    _paint_object(image, 50, 40, 28, 0)
    blocks = dense_block_map(image[None, None], trained.config, trained.stride)
    ref = F.conv2d(blocks, trained._filters, trained.bias, dilation=8 // trained.stride)[0].amax(0)
    out = trained.score_map(image[None, None])
    assert out.shape == ((90 - 40) // 4 + 1, (110 - 40) // 4 + 1)
    torch.testing.assert_close(out, ref, rtol=1e-4, atol=1e-4)


def test_score_map_close_to_patch_scores(trained: HOGDetector) -> None:
    """Dense windows differ from cropped patches only on the window's outer pixel ring."""
    image = _background(80, 96, torch.Generator().manual_seed(8))
    _paint_object(image, 48, 40, 28, 1)
    smap = trained.score_map(image[None, None])
    crops = torch.stack([image[y * 4 : y * 4 + 40, x * 4 : x * 4 + 40] for y in range(smap.shape[0]) for x in range(smap.shape[1])])
    direct = trained.score_patches(crops[:, None]).reshape(smap.shape)
    corr = torch.corrcoef(torch.stack([smap.flatten(), direct.flatten()]))[0, 1]
    assert corr > 0.95
    assert torch.equal(torch.tensor(divmod(int(smap.argmax()), smap.shape[1])), torch.tensor(divmod(int(direct.argmax()), smap.shape[1])))


def test_generic_score_map_matches_patches() -> None:
    """The base-class fallback crops every window: it equals score_patches exactly."""

    class Mean(PatchDetector):
        kind = "test_mean"
        window = 8
        stride = 3

        def score_patches(self, patches: torch.Tensor) -> torch.Tensor:
            return patches.mean((1, 2, 3))

        def state_dict(self) -> dict:
            return {}

        @classmethod
        def from_state_dict(cls, state: dict) -> "Mean":
            return cls()

    image = torch.rand(1, 1, 20, 27, generator=torch.Generator().manual_seed(0))
    out = Mean().score_map(image)
    ref = F.avg_pool2d(image, 8, 3)[0, 0]
    torch.testing.assert_close(out, ref)


def test_detects_objects_in_a_frame(trained: HOGDetector) -> None:
    frame = _background(200, 260, torch.Generator().manual_seed(21))
    truths = [(70.0, 60.0, 28.0, 0), (190.0, 140.0, 36.0, 1)]  # centre x, centre y, longest side, kind
    for cx, cy, size, kind in truths:
        _paint_object(frame, cx, cy, size, kind)
    trained.box_in_window = (6.0, 6.0, 28.0, 28.0)
    try:
        dets = detect_multiscale(trained, frame, scales=(1.0, 0.78), max_detections=5)
    finally:
        trained.box_in_window = None
    assert dets.shape[1] == 5 and dets.shape[0] >= 2
    assert torch.all(dets[:-1, 4] >= dets[1:, 4])
    gt = torch.tensor([[cx - s / 2, cy - s / 2, s, s] for cx, cy, s, _ in truths])
    iou = box_iou(box_convert(dets[:2, :4], "xywh", "xyxy"), box_convert(gt, "xywh", "xyxy"))
    assert (iou.amax(1) >= 0.5).all(), f"top-2 detections {dets[:2].tolist()} vs truths {gt.tolist()}"
    assert dets[0, 4] > 0 and dets[1, 4] > 0


def test_detect_multiscale_input_checks(trained: HOGDetector) -> None:
    assert detect_multiscale(trained, torch.rand(20, 30)).shape == (0, 5)  # smaller than the window
    with pytest.raises(ValueError, match="scales"):
        detect_multiscale(trained, torch.rand(60, 60), scales=[1.0, -1.0])
    with pytest.raises(ValueError, match="grayscale"):
        detect_multiscale(trained, torch.rand(3, 60, 60))


def test_checkpoint_roundtrip_with_weights_only(trained: HOGDetector, tmp_path) -> None:
    trained.box_in_window = (6.0, 8.0, 28.0, 24.0)
    try:
        path = save_detector(trained, tmp_path / "det" / "hog.pt")
    finally:
        trained.box_in_window = None
    payload = torch.load(path, weights_only=True)  # plain types only
    assert payload["kind"] == "hog"
    loaded = load_detector(path)
    assert isinstance(loaded, HOGDetector) and loaded.box_in_window == (6.0, 8.0, 28.0, 24.0)
    patches = _problem(seed=9, n_pos=5, n_neg=10)[0]
    torch.testing.assert_close(loaded.score_patches(patches), trained.score_patches(patches))
    assert loaded.config == trained.config and loaded.stride == trained.stride


def test_corrupt_and_mismatched_checkpoints(trained: HOGDetector, tmp_path) -> None:
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"not a checkpoint at all")
    with pytest.raises(ValueError, match="garbage.pt.*not a readable"):
        load_detector(garbage)
    good = save_detector(trained, tmp_path / "good.pt")
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(good.read_bytes()[:200])
    with pytest.raises(ValueError, match="truncated.pt"):
        load_detector(truncated)
    other = tmp_path / "other.pt"
    torch.save({"weights": torch.zeros(3)}, other)
    with pytest.raises(ValueError, match="other.pt is not a synthaug detector"):
        load_detector(other)
    payload = torch.load(good, weights_only=True)
    payload["state"]["weights"] = torch.zeros(3, 100)
    bad_shape = tmp_path / "bad_shape.pt"
    torch.save(payload, bad_shape)
    with pytest.raises(ValueError, match=r"bad_shape.pt: state does not match a 'hog' detector.*576"):
        load_detector(bad_shape)
    payload["kind"] = "martian"
    torch.save(payload, tmp_path / "kind.pt")
    with pytest.raises(ValueError, match="unknown detector kind 'martian'"):
        load_detector(tmp_path / "kind.pt")
    with pytest.raises(FileNotFoundError):
        load_detector(tmp_path / "missing.pt")


def test_registry() -> None:
    assert "hog" in list_detectors()
    assert get_detector_class("hog") is HOGDetector
    with pytest.raises(ValueError, match="PatchDetector subclass"):
        register_detector(int)  # type: ignore[arg-type]


def test_constructor_and_fit_validation() -> None:
    with pytest.raises(ValueError, match=r"weights must be \(K >= 1, 576\)"):
        HOGDetector(torch.zeros(2, 10), torch.zeros(2))
    with pytest.raises(ValueError, match="stride must divide"):
        HOGDetector(torch.zeros(1, 576), torch.zeros(1), stride=3)
    with pytest.raises(ValueError, match="positives is empty"):
        HOGDetector.fit(torch.zeros(0, 1, 40, 40), torch.rand(4, 1, 40, 40))
    with pytest.raises(ValueError, match="components"):
        HOGDetector.fit(torch.rand(2, 1, 40, 40), torch.rand(4, 1, 40, 40), components=0)


def test_fit_accepts_uint8_seed_patches() -> None:
    pos, neg = _problem(seed=11, n_pos=12, n_neg=40)
    det = HOGDetector.fit((pos[:, 0] * 255).round().to(torch.uint8), (neg[:, 0] * 255).round().to(torch.uint8), components=1, mining_rounds=0)
    assert (det.score_patches(pos) > det.score_patches(neg).median()).float().mean() > 0.9


def test_svm_against_separable_reference() -> None:
    # 1-D separable data: the max-margin boundary lies halfway between the closest points
    x = torch.tensor([[-3.0], [-2.0], [2.0], [4.0]])
    y = torch.tensor([-1.0, -1.0, 1.0, 1.0])
    w, b = train_linear_svm(x, y, regularization=1e-4)
    assert float(-b / w[0]) == pytest.approx(0.0, abs=1e-2)
    assert float(w[0] * 2 + b) == pytest.approx(1.0, abs=0.05)  # support vectors sit on the margin


def test_svm_sample_weight_counts_as_repeated_samples() -> None:
    # a weight of k is the sample k times (the class halves are shared by weight, as by count)
    g = torch.Generator().manual_seed(4)
    x = torch.randn(30, 5, generator=g)
    y = torch.where(x[:, 0] + 0.3 * torch.randn(30, generator=g) > 0, 1.0, -1.0)
    sw = torch.ones(30)
    sw[:4] = 3.0
    w1, b1 = train_linear_svm(x, y, regularization=1e-2, sample_weight=sw)
    rep = torch.cat([x, x[:4], x[:4]]), torch.cat([y, y[:4], y[:4]])
    w2, b2 = train_linear_svm(*rep, regularization=1e-2)
    torch.testing.assert_close(w1, w2, atol=1e-4, rtol=1e-3)
    torch.testing.assert_close(b1, b2, atol=1e-4, rtol=1e-3)
    w3, b3 = train_linear_svm(x, y, regularization=1e-2, sample_weight=torch.ones(30))
    w4, b4 = train_linear_svm(x, y, regularization=1e-2)
    torch.testing.assert_close(w3, w4, atol=1e-6, rtol=1e-5)
    with pytest.raises(ValueError, match="sample_weight"):
        train_linear_svm(x, y, sample_weight=-sw)
    with pytest.raises(ValueError, match="no weight"):
        train_linear_svm(x, y, sample_weight=torch.where(y > 0, 0.0, 1.0))


def test_positive_weights_zero_drops_those_positives() -> None:
    # one component (no k-means choice): positives of weight 0 train the same filter as leaving them out
    pos, neg = _problem(seed=13, n_pos=16, n_neg=40)
    extra = torch.rand(8, 1, 40, 40, generator=torch.Generator().manual_seed(2))
    w = torch.cat([torch.ones(16), torch.zeros(8)])
    a = HOGDetector.fit(torch.cat([pos, extra]), neg, components=1, mining_rounds=0, positive_weights=w)
    b = HOGDetector.fit(pos, neg, components=1, mining_rounds=0)
    torch.testing.assert_close(a.weights, b.weights, atol=1e-4, rtol=1e-3)
    with pytest.raises(ValueError, match="one per positive"):
        HOGDetector.fit(pos, neg, components=1, mining_rounds=0, positive_weights=torch.ones(3))


def test_kmeans_recovers_separated_clusters() -> None:
    g = torch.Generator().manual_seed(0)
    centres = torch.tensor([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
    x = torch.cat([c + 0.5 * torch.randn(30, 2, generator=g) for c in centres])
    labels = kmeans(x, 3, generator=torch.Generator().manual_seed(1))
    for block in labels.reshape(3, 30):
        assert (block == block[0]).all()
    assert len(set(labels.tolist())) == 3


def _blobs() -> torch.Tensor:
    """240 points in 8-D from 6 Gaussian blobs: k = 3 has several k-means minima (single runs from generator seeds
    0-9 end at inertia 5,208 / 5,269 / 5,575 / 5,579 / 5,696 / 5,905)."""
    import numpy as np

    rng = np.random.default_rng(0)
    c = rng.standard_normal((6, 8)) * 3
    return torch.tensor(np.concatenate([ci + rng.standard_normal((40, 8)) for ci in c]), dtype=torch.float32)


def test_kmeans_inertia_against_numpy() -> None:
    import numpy as np

    x = _blobs()
    labels = torch.arange(len(x)) % 4
    xn, ln = x.double().numpy(), labels.numpy()
    expected = sum(((xn[ln == j] - xn[ln == j].mean(0)) ** 2).sum() for j in range(4))
    assert math.isclose(kmeans_inertia(x, labels), expected, rel_tol=1e-12)
    assert math.isclose(kmeans_inertia(x, labels + 7), expected, rel_tol=1e-12)  # labels need not start at 0


def test_kmeans_restarts_keep_the_lowest_inertia_run() -> None:
    """``restarts = R`` is the lowest-inertia of R single runs drawn in turn from the same generator (the first of
    them is ``restarts = 1``'s run), so it is never worse, and on these blobs it is better for some seeds."""
    from synthaug.detectors.hog_dpm import _kmeans_once

    x = _blobs()
    single, best = [], []
    for seed in range(10):
        g = torch.Generator().manual_seed(seed)
        runs = [_kmeans_once(x, 3, generator=g, iterations=30) for _ in range(10)]
        first = kmeans(x, 3, generator=torch.Generator().manual_seed(seed))
        torch.testing.assert_close(first, runs[0][0])
        chosen = kmeans(x, 3, generator=torch.Generator().manual_seed(seed), restarts=10)
        torch.testing.assert_close(chosen, min(runs, key=lambda r: r[1])[0])
        single.append(kmeans_inertia(x, first))
        best.append(kmeans_inertia(x, chosen))
    assert all(b <= s + 1e-6 for b, s in zip(best, single))
    assert max(s - b for b, s in zip(best, single)) > 100.0
    assert max(best) - min(best) < 1e-3 < max(single) - min(single)  # ten runs reach one minimum from every seed
    with pytest.raises(ValueError, match="restarts"):
        kmeans(x, 3, generator=torch.Generator().manual_seed(0), restarts=0)


def test_hog_fit_initialises_its_components_with_the_restarted_kmeans(monkeypatch: pytest.MonkeyPatch) -> None:
    import synthaug.detectors.hog_dpm as hd

    seen = []
    real = hd.kmeans
    monkeypatch.setattr(hd, "kmeans", lambda *a, **k: seen.append(k["restarts"]) or real(*a, **k))
    pos, neg = _problem(seed=3, n_pos=12, n_neg=30)
    HOGDetector.fit(pos, neg, components=2, mining_rounds=0)
    HOGDetector.fit(pos, neg, components=2, mining_rounds=0, kmeans_restarts=1)
    assert seen == [10, 1]


def test_box_in_window_from_boxes() -> None:
    x, y, w, h = box_in_window_from_boxes(torch.tensor([[0.0, 0.0, 40.0, 20.0]]), window=40, object_fraction=0.5)
    assert (x, y, w, h) == (10.0, 15.0, 20.0, 10.0)
    with pytest.raises(ValueError, match="object_fraction"):
        box_in_window_from_boxes(torch.tensor([[0.0, 0.0, 4.0, 2.0]]), object_fraction=0)
    assert math.isclose(sum(box_in_window_from_boxes(torch.tensor([[1.0, 1.0, 5.0, 5.0]]))[2:]), 56.0)


def test_mining_skips_windows_touching_ignore_boxes() -> None:
    """Frames with labelled objects can serve as backgrounds: the object's windows are never mined."""
    from synthaug.detectors.hog_dpm import _mine

    pos, neg = _problem(seed=12, n_pos=20, n_neg=40)
    det = HOGDetector.fit(pos, neg, components=1, mining_rounds=0)
    frame = _background(80, 80, torch.Generator().manual_seed(3))
    _paint_object(frame, 40, 40, 28, 0)
    args = (det.weights, det.bias)
    empty = torch.zeros(0, 576)
    everything = _mine(empty, empty, *args, [frame], None, 40, 4, det.config, (1.0,), 10_000)
    # the object's window scores high: without an ignore box it is mined
    obj_feat = det.features(frame[20:60, 20:60][None, None])
    assert torch.cdist(obj_feat, everything).min() < 1.0
    masked = _mine(empty, empty, *args, [frame], [torch.tensor([[26.0, 26.0, 28.0, 28.0]])], 40, 4, det.config, (1.0,), 10_000)
    # every 40-px window of an 80x80 frame touches a box around its centre: nothing is left to mine
    assert everything.shape[0] > 0 and masked.shape[0] == 0
    corner = _mine(empty, empty, *args, [frame], [torch.tensor([[0.0, 0.0, 3.0, 3.0]])], 40, 4, det.config, (1.0,), 10_000)
    assert torch.cdist(obj_feat, corner).min() < 1.0  # a far box does not hide the object's window
    with pytest.raises(ValueError, match="ignore_boxes"):
        HOGDetector.fit(pos, neg, background_images=[frame], ignore_boxes=[None, None])
