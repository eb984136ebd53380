"""AdaBoost of Levi–Weiss stumps: stump search and boosting against numpy, dense scoring against crops."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from synthaug.detectors.adaboost import AdaBoostDetector, best_stumps, train_adaboost, transfer_update
from synthaug.detectors.base import load_detector, save_detector
from synthaug.detectors.toy import toy_frame, toy_patches
from synthaug.detectors.weak_learners import WeakLearners, edge_orientation_energy, exhaustive_candidates


def _np_best_stump(f: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[float, float, float]:
    """Brute force: every midpoint threshold, both polarities."""
    w = w / w.sum()
    vals = np.unique(f)
    best = (2.0, 0.0, 1.0)
    for a, b in zip(vals[:-1], vals[1:]):
        tau = (a + b) / 2
        for pol in (1.0, -1.0):
            pred = (pol * (f - tau) > 0).astype(float)
            err = float((w * (pred != y)).sum())
            if err < best[0] - 1e-12:
                best = (err, tau, pol)
    return best


def test_best_stumps_match_brute_force() -> None:
    rng = np.random.default_rng(0)
    n, m = 40, 12
    f = rng.random((n, m)).round(2)  # ties on purpose
    f[:, 3] = 0.5  # a constant column
    y = (rng.random(n) < 0.4).astype(float)
    w = rng.random(n)
    err, tau, pol = best_stumps(torch.from_numpy(f), torch.from_numpy(y).long(), torch.from_numpy(w))
    assert err[3] == 0.5
    for j in range(m):
        if j == 3:
            continue
        ref_err, _, _ = _np_best_stump(f[:, j], y, w)
        assert err[j].item() == pytest.approx(ref_err, abs=1e-6)
        # the returned threshold/polarity achieve that error
        pred = (pol[j].item() * (f[:, j] - tau[j].item()) > 0).astype(float)
        assert float((w / w.sum() * (pred != y)).sum()) == pytest.approx(ref_err, abs=1e-6)


def _np_adaboost(f: np.ndarray, y: np.ndarray, rounds: int,
                 positive_weights: np.ndarray | None = None) -> tuple[list[int], list[float]]:
    """Textbook discrete AdaBoost (class-balanced start; the positives' half split by ``positive_weights`` when
    given), returns chosen columns and α."""
    n_pos, n_neg = y.sum(), (1 - y).sum()
    w = np.where(y == 1, 0.5 / n_pos, 0.5 / n_neg)
    if positive_weights is not None:
        w[y == 1] = 0.5 * positive_weights / positive_weights.sum()
    chosen, alphas = [], []
    for _ in range(rounds):
        errs = [_np_best_stump(f[:, j], y, w) for j in range(f.shape[1])]
        j = int(np.argmin([e[0] for e in errs]))
        err, tau, pol = errs[j]
        alpha = 0.5 * math.log((1 - err) / err)
        h = (pol * (f[:, j] - tau) > 0).astype(float)
        w = w * np.exp(-alpha * (2 * y - 1) * (2 * h - 1))
        w = w / w.sum()
        chosen.append(j)
        alphas.append(alpha)
    return chosen, alphas


def test_train_adaboost_matches_numpy_reference() -> None:
    pos, neg = toy_patches(20, 30, seed=3)
    det = train_adaboost(pos, neg, n_rounds=5, candidates=40, step=8, seed=1)
    # rebuild the same candidate subset and feature matrix independently
    rects, orients = exhaustive_candidates(40, 4, step=8, min_size=4)
    pick = torch.randperm(len(rects), generator=torch.Generator().manual_seed(1))[:40].sort().values
    rects, orients = rects[pick], orients[pick]
    f = edge_orientation_energy(torch.cat([pos, neg]).double(), rects, orients).numpy()
    y = np.r_[np.ones(20), np.zeros(30)]
    chosen, alphas = _np_adaboost(f, y, 5)
    assert det.learners.rects.tolist() == rects[chosen].tolist()
    assert det.learners.orientations.tolist() == orients[chosen].tolist()
    np.testing.assert_allclose(det.alphas.numpy(), alphas, rtol=1e-4)


def test_positive_weights_start_the_boosting_as_the_numpy_reference_and_as_repeated_samples() -> None:
    pos, neg = toy_patches(20, 30, seed=3)
    pw = torch.from_numpy(np.random.default_rng(0).uniform(0.2, 3.0, 20))
    det = train_adaboost(pos, neg, n_rounds=5, candidates=40, step=8, seed=1, positive_weights=pw)
    rects, orients = exhaustive_candidates(40, 4, step=8, min_size=4)
    pick = torch.randperm(len(rects), generator=torch.Generator().manual_seed(1))[:40].sort().values
    f = edge_orientation_energy(torch.cat([pos, neg]).double(), rects[pick], orients[pick]).numpy()
    chosen, alphas = _np_adaboost(f, np.r_[np.ones(20), np.zeros(30)], 5, pw.numpy())
    assert det.learners.rects.tolist() == rects[pick][chosen].tolist()
    np.testing.assert_allclose(det.alphas.numpy(), alphas, rtol=1e-4)
    # a weight of 2 boosts as the patch twice would; all-equal weights as no weights
    w2 = torch.ones(20, dtype=torch.float64)
    w2[:5] = 2.0
    a = train_adaboost(pos, neg, n_rounds=8, candidates=60, seed=2, positive_weights=w2)
    b = train_adaboost(torch.cat([pos, pos[:5]]), neg, n_rounds=8, candidates=60, seed=2)
    assert a.learners.rects.tolist() == b.learners.rects.tolist()
    torch.testing.assert_close(a.alphas, b.alphas)
    c = train_adaboost(pos, neg, n_rounds=8, candidates=60, seed=2, positive_weights=torch.full((20,), 3.0))
    d = train_adaboost(pos, neg, n_rounds=8, candidates=60, seed=2)
    assert c.learners.rects.tolist() == d.learners.rects.tolist()
    torch.testing.assert_close(c.alphas, d.alphas)
    for bad in (torch.ones(19), -torch.ones(20), torch.zeros(20), torch.full((20,), float("nan"))):
        with pytest.raises(ValueError, match="positive_weights"):
            train_adaboost(pos, neg, n_rounds=2, candidates=10, positive_weights=bad)


def _np_tradaboost(f: np.ndarray, y: np.ndarray, source: np.ndarray, rounds: int) -> tuple[list[int], list[float]]:
    """Dynamic-TrAdaBoost written from the papers (Dai et al. 2007; Al-Stouhi and Reddy 2011): the stump chosen on
    every weighted sample, its error and α on the target samples only; target misses x (1 - ε) / ε, source samples x
    2 (1 - ε) and their misses x β more; a stump with target error >= 1/2 is not kept and the source weights x β."""
    n_pos, n_neg = y.sum(), (1 - y).sum()
    w = np.where(y == 1, 0.5 / n_pos, 0.5 / n_neg)
    beta = 1 / (1 + math.sqrt(2 * math.log(source.sum()) / rounds))
    chosen, alphas = [], []
    for _ in range(rounds):
        errs = [_np_best_stump(f[:, j], y, w) for j in range(f.shape[1])]
        j = int(np.argmin([e[0] for e in errs]))
        _, tau, pol = errs[j]
        miss = (pol * (f[:, j] - tau) > 0).astype(float) != y
        t = ~source
        eps = float((w[t] * miss[t]).sum() / w[t].sum())
        if eps >= 0.5 - 1e-12:  # (1/2 to float rounding: a stump that repeats the last one's target misses)
            w = np.where(source, w * beta, w)
        else:
            w = w * np.where(source, 2 * (1 - eps) * np.where(miss, beta, 1.0), np.where(miss, (1 - eps) / eps, 1.0))
            chosen.append(j)
            alphas.append(0.5 * math.log((1 - eps) / eps))
        w = w / w.sum()
    return chosen, alphas


def test_source_positives_boost_as_the_numpy_dynamic_tradaboost_reference() -> None:
    pos, neg = toy_patches(20, 30, seed=3)
    src = toy_patches(12, 12, seed=8)
    added = torch.cat([src[0][:6], src[1][:6]])  # half object-like, half background-like "synthetic" positives
    det = train_adaboost(torch.cat([pos, added]), neg, n_rounds=6, candidates=40, step=8, seed=1, source_positives=12)
    rects, orients = exhaustive_candidates(40, 4, step=8, min_size=4)
    pick = torch.randperm(len(rects), generator=torch.Generator().manual_seed(1))[:40].sort().values
    f = edge_orientation_energy(torch.cat([pos, added, neg]).double(), rects[pick], orients[pick]).numpy()
    y = np.r_[np.ones(32), np.zeros(30)]
    source = np.r_[np.zeros(20), np.ones(12), np.zeros(30)].astype(bool)
    chosen, alphas = _np_tradaboost(f, y, source, 6)
    assert len(chosen) >= 3
    assert det.learners.rects.tolist() == rects[pick][chosen].tolist()
    np.testing.assert_allclose(det.alphas.numpy(), alphas, rtol=1e-4)
    # 0 source positives: plain AdaBoost
    a = train_adaboost(pos, neg, n_rounds=5, candidates=40, seed=2, source_positives=0)
    b = train_adaboost(pos, neg, n_rounds=5, candidates=40, seed=2)
    assert a.learners.rects.tolist() == b.learners.rects.tolist()
    torch.testing.assert_close(a.alphas, b.alphas)
    for bad in (-1, 20, 2.5, True):  # all positives from the source, or not a count
        with pytest.raises(ValueError, match="source_positives"):
            train_adaboost(pos, neg, n_rounds=2, candidates=10, source_positives=bad)


def test_cascade_positives_set_the_thresholds_from_the_real_positives_only() -> None:
    """``cascade_positives``: the same stumps, each stage's threshold the minimum partial score of the first k
    positives minus 0.3 of the accumulated α (numpy reference from the stumps' own features); added positives that
    look like background no longer loosen the stages, so fewer background windows are scored to the end."""
    pos, neg = toy_patches(60, 120, seed=2)
    bad = toy_patches(10, 10, seed=5)[1]  # 10 "added positives" that are background patches
    both = torch.cat([pos, bad])
    kw = dict(n_rounds=30, candidates=300, seed=0, source_positives=len(bad))
    every = train_adaboost(both, neg, **kw)
    real = train_adaboost(both, neg, cascade_positives=len(pos), **kw)
    assert real.learners.rects.tolist() == every.learners.rects.tolist()
    torch.testing.assert_close(real.alphas, every.alphas)
    wl = real.learners
    f = edge_orientation_energy(pos.double(), wl.rects, wl.orientations, wl.n_bins, wl.eps, wl.floor).numpy()
    h = (f - wl.thresholds.double().numpy()) * wl.polarity.double().numpy() > 0
    alphas = wl.weights.double().numpy()
    partial = np.cumsum((2 * h - 1) * alphas, axis=1)
    ends = np.arange(real.stage_size, len(alphas) + real.stage_size, real.stage_size).clip(max=len(alphas)) - 1
    ref = partial[:, ends].min(0) - 0.3 * np.cumsum(alphas)[ends]
    np.testing.assert_allclose(real.rejection[:-1].numpy(), ref[:-1], atol=1e-6)
    assert real.rejection[-1] == -math.inf
    assert (every.rejection <= real.rejection + 1e-9).all()  # the minimum over more positives
    assert (every.rejection[:-1] < real.rejection[:-1] - 1e-6).any()  # the background "positives" set some stages
    frame, _ = toy_frame(240, 320, n_objects=4, seed=7)
    real.cascade = False
    full = real.score_map(frame)  # the same stumps: the same full scores for both
    real.cascade = True
    kept_real = ((real.score_map(frame) - full).abs() < 1e-5).float().mean()
    kept_every = ((every.score_map(frame) - full).abs() < 1e-5).float().mean()
    assert kept_real < kept_every
    for bad_k in (0, 71, 2.5, True):
        with pytest.raises(ValueError, match="cascade_positives"):
            train_adaboost(both, neg, n_rounds=2, candidates=10, cascade_positives=bad_k)


def test_source_positives_that_look_like_background_cost_less_with_the_transfer_rule() -> None:
    """Added "positives" that are background patches pull plain AdaBoost's stumps off the objects; the transfer rule
    measures α on the real samples and lets those patches lose weight (held-out ROC-AUC from scipy's U statistic)."""
    from scipy.stats import mannwhitneyu

    pos, neg = toy_patches(60, 120, seed=2)
    bad = toy_patches(10, 120, seed=5)[1]
    test_pos, test_neg = toy_patches(200, 400, seed=7)

    def auc(det: AdaBoostDetector) -> float:
        s1, s0 = det.score_patches(test_pos).numpy(), det.score_patches(test_neg).numpy()
        return float(mannwhitneyu(s1, s0).statistic) / (len(s1) * len(s0))

    plain = auc(train_adaboost(torch.cat([pos, bad]), neg, n_rounds=40, candidates=300, seed=0))
    transfer = auc(train_adaboost(torch.cat([pos, bad]), neg, n_rounds=40, candidates=300, seed=0,
                                  source_positives=len(bad)))
    clean = auc(train_adaboost(pos, neg, n_rounds=40, candidates=300, seed=0))
    assert plain < clean - 0.1  # measured 0.837 against 0.995
    assert transfer > plain + 0.1 and transfer > clean - 0.02  # measured 0.993


@pytest.fixture(scope="module")
def trained() -> AdaBoostDetector:
    pos, neg = toy_patches(150, 300, seed=0)
    return train_adaboost(pos, neg, n_rounds=40, candidates=3000, seed=0)


def test_generalises_on_toy_data(trained: AdaBoostDetector) -> None:
    pos, neg = toy_patches(100, 100, seed=99)
    s = trained.score_patches(torch.cat([pos, neg]))
    acc = ((s[:100] > 0).float().mean() + (s[100:] <= 0).float().mean()) / 2
    assert acc > 0.9, acc
    assert (trained.alphas > 0).all()


@pytest.mark.parametrize("size", [(200, 280), (163, 201)])
def test_score_map_equals_scoring_every_crop(trained: AdaBoostDetector, size: tuple[int, int]) -> None:
    frame, _ = toy_frame(*size, n_objects=3, seed=5)
    trained.cascade = False
    try:
        dense = trained.score_map(frame)
    finally:
        trained.cascade = True
    cols = torch.nn.functional.unfold(frame, 40, stride=trained.stride)[0].T.reshape(-1, 1, 40, 40)
    ref = trained.score_patches(cols).reshape(dense.shape)
    assert dense.shape == ((size[0] - 40) // 4 + 1, (size[1] - 40) // 4 + 1)
    torch.testing.assert_close(dense, ref, atol=1e-5, rtol=0)


def test_score_map_off_grid_learners_match_crops() -> None:
    # random rectangles (not on a 4-px grid): the g = 1 integral-image path
    g = torch.Generator().manual_seed(3)
    wl = WeakLearners.random(25, generator=g, reference=toy_patches(20, 20, seed=1)[0])
    wl.weights = torch.rand(25, generator=g) + 0.1
    det = AdaBoostDetector(wl, stride=3, cascade=False)
    assert det._grid() == 1
    frame, _ = toy_frame(120, 160, 2, seed=2)
    dense = det.score_map(frame)
    cols = torch.nn.functional.unfold(frame, 40, stride=3)[0].T.reshape(-1, 1, 40, 40)
    torch.testing.assert_close(dense, det.score_patches(cols).reshape(dense.shape), atol=1e-5, rtol=0)


def test_cascade_is_a_lower_bound_and_keeps_positives(trained: AdaBoostDetector) -> None:
    frame, _ = toy_frame(240, 320, n_objects=4, seed=7)
    trained.cascade = False
    exact = trained.score_map(frame)
    trained.cascade = True
    fast = trained.score_map(frame)
    assert (fast <= exact + 1e-5).all()
    survived = (fast - exact).abs() < 1e-5
    assert survived.float().mean() < 0.5  # the cascade drops most background windows
    ends = torch.tensor(trained._stage_ends()) - 1
    # every training positive passes every stage
    pos, _ = toy_patches(150, 0, seed=0)
    assert (trained.partial_scores(pos)[:, ends[:-1]] >= trained.rejection[:-1]).all()
    # and unseen positives that the full classifier accepts are rarely rejected early
    unseen, _ = toy_patches(300, 0, seed=123)
    part = trained.partial_scores(unseen)
    rejected = (part[:, ends[:-1]] < trained.rejection[:-1]).any(1)
    assert (rejected & (part[:, -1] > 0)).float().mean() < 0.05


def test_detect_multiscale_finds_toy_objects(trained: AdaBoostDetector) -> None:
    from torchvision.ops import box_convert, box_iou

    from synthaug.detectors.sliding import detect_multiscale

    frame, boxes = toy_frame(200, 240, n_objects=3, seed=11)
    dets = detect_multiscale(trained, frame, scales=(1.0,), score_threshold=0.0, nms_iou=0.3)
    assert len(dets) >= 3
    iou = box_iou(box_convert(boxes, "xywh", "xyxy"), box_convert(dets[:, :4], "xywh", "xyxy"))
    assert (iou.max(1).values >= 0.5).all()


def test_small_image_and_save_load(trained: AdaBoostDetector, tmp_path) -> None:
    assert trained.score_map(torch.rand(1, 1, 30, 100)).shape == (0, 16)
    path = save_detector(trained, tmp_path / "ada.pt")
    back = load_detector(path)
    assert isinstance(back, AdaBoostDetector) and back.stride == trained.stride
    frame, _ = toy_frame(120, 160, 2, seed=3)
    torch.testing.assert_close(back.score_map(frame), trained.score_map(frame))
    raw = torch.load(path, weights_only=True)
    raw["state"]["rejection"] = torch.zeros(1)
    torch.save(raw, tmp_path / "bad.pt")
    with pytest.raises(ValueError, match="rejection"):
        load_detector(tmp_path / "bad.pt")
    (tmp_path / "corrupt.pt").write_bytes(path.read_bytes()[:100])
    with pytest.raises(ValueError, match="corrupt.pt"):
        load_detector(tmp_path / "corrupt.pt")


def test_bad_inputs() -> None:
    pos, neg = toy_patches(4, 4, seed=0)
    with pytest.raises(ValueError, match="negatives"):
        train_adaboost(pos, neg[:0])
    with pytest.raises(ValueError, match="candidates"):
        train_adaboost(pos, neg, candidates="all")
    with pytest.raises(ValueError, match="n_rounds"):
        train_adaboost(pos, neg, n_rounds=0)
    with pytest.raises(ValueError, match="no weak learner"):
        train_adaboost(pos, pos.clone(), n_rounds=3, candidates=50)
    with pytest.raises(ValueError, match=r"\(N, 1, 40, 40\)"):
        AdaBoostDetector(WeakLearners.random(3, generator=torch.Generator())).score_patches(torch.rand(2, 1, 20, 20))


# ----------------------------------------------------------------- the energy floor
def test_energy_floor_matches_a_numpy_energy_and_keeps_dense_scoring_exact() -> None:
    """E = G_o / (Σ G + ε + floor |R|), against per-pixel numpy sums; training, score_patches, the dense map (both
    paths, cascade on and off) and the reference map agree with a floor; save / load keeps it; older states load."""
    pos, neg = toy_patches(20, 30, seed=3)
    rects, orients = exhaustive_candidates(40, 4, step=8, min_size=4)
    x = torch.cat([pos, neg]).double()
    floor = 0.01
    e = edge_orientation_energy(x, rects, orients, 4, 1e-3, floor).numpy()
    # numpy: central differences of the interior pixels, magnitude binned by unsigned angle, as orientation_maps
    a = x[:, 0].numpy()
    gx = np.zeros_like(a)
    gy = np.zeros_like(a)
    gx[:, 1:-1, 1:-1] = (a[:, 1:-1, 2:] - a[:, 1:-1, :-2]) / 2
    gy[:, 1:-1, 1:-1] = (a[:, 2:, 1:-1] - a[:, :-2, 1:-1]) / 2
    from synthaug.detectors.weak_learners import orientation_maps

    maps = orientation_maps(x, 4).numpy()  # (B, K, H, W), checked against numpy in test_weak_learners
    for m in range(0, len(rects), 37):
        y0, x0, h, w = rects[m].tolist()
        go = maps[:, orients[m], y0:y0 + h, x0:x0 + w].sum((1, 2))
        g = maps[:, :, y0:y0 + h, x0:x0 + w].sum((1, 2, 3))
        np.testing.assert_allclose(e[:, m], go / (g + 1e-3 + floor * h * w), rtol=1e-9)
    mag = np.sqrt(gx**2 + gy**2)[:, 1:-1, 1:-1]
    np.testing.assert_allclose(maps.sum(1)[:, 1:-1, 1:-1], mag, atol=1e-6)
    assert (e < edge_orientation_energy(x, rects, orients, 4, 1e-3).numpy() + 1e-12).all()  # a floor only lowers E

    det = train_adaboost(pos, neg, n_rounds=15, candidates=200, seed=0, energy_floor=floor)
    assert det.learners.floor == floor
    frame, _ = toy_frame(163, 201, n_objects=3, seed=5)
    cols = torch.nn.functional.unfold(frame, 40, stride=det.stride)[0].T.reshape(-1, 1, 40, 40)
    det.cascade = False
    dense = det.score_map(frame)
    torch.testing.assert_close(dense, det.score_patches(cols).reshape(dense.shape), atol=1e-5, rtol=0)
    torch.testing.assert_close(dense, det._score_map_reference(frame), atol=1e-5, rtol=0)
    det.cascade = True
    torch.testing.assert_close(det.score_map(frame), det._score_map_reference(frame), atol=1e-5, rtol=0)
    state = det.learners.state_dict()
    assert WeakLearners.from_state_dict(state).floor == floor
    assert WeakLearners.from_state_dict({k: v for k, v in state.items() if k != "floor"}).floor == 0.0
    with pytest.raises(ValueError, match="floor"):
        WeakLearners(**{**{k: v for k, v in state.items()}, "floor": -1.0})
    with pytest.raises(ValueError, match="floor"):
        edge_orientation_energy(x, rects, orients, 4, 1e-3, float("nan"))


def test_energy_floor_silences_faint_structure_that_the_paper_energy_shows_at_full_strength() -> None:
    """The same edge at 1/50 of the contrast: the paper's E is unchanged (contrast-invariant), a floor at the
    faint edge's gradient level lowers its energy by about half and leaves the strong edge's nearly unchanged."""
    strong = torch.zeros(1, 1, 40, 40, dtype=torch.float64)
    strong[..., :, 20:] = 0.5
    faint = strong / 50
    rects, orients = torch.tensor([[4, 12, 16, 16]]), torch.tensor([0])  # a rectangle across the vertical edge
    e0 = [edge_orientation_energy(p, rects, orients, 4, 1e-3).item() for p in (strong, faint)]
    from synthaug.detectors.weak_learners import orientation_maps

    level = float(orientation_maps(faint, 4)[..., 4:20, 12:28].sum()) / 256  # the faint rectangle's mean magnitude
    e1 = [edge_orientation_energy(p, rects, orients, 4, 1e-3, level).item() for p in (strong, faint)]
    assert e0[0] == pytest.approx(e0[1], rel=0.02)
    assert e1[1] == pytest.approx(e0[1] / 2, rel=0.05) and e1[0] == pytest.approx(e0[0], rel=0.03)


def test_gradient_level_is_the_median_of_the_patches_mean_magnitude() -> None:
    from synthaug.detectors.adaboost import gradient_level

    g = torch.Generator().manual_seed(0)
    x = torch.rand(7, 1, 40, 40, generator=g, dtype=torch.float64) * torch.linspace(0.1, 1, 7).view(7, 1, 1, 1)
    a = x[:, 0].numpy()
    gx = (a[:, 1:-1, 2:] - a[:, 1:-1, :-2]) / 2
    gy = (a[:, 2:, 1:-1] - a[:, :-2, 1:-1]) / 2
    assert gradient_level(x) == pytest.approx(float(np.median(np.sqrt(gx**2 + gy**2).mean((1, 2)))), rel=1e-6)


def test_transfer_update_against_the_hand_computed_factors() -> None:
    rng = np.random.default_rng(3)
    w = rng.uniform(0.1, 1.0, 10)
    miss = rng.uniform(size=10) < 0.4
    source = np.arange(10) >= 6
    eps, beta = 0.2, 0.7
    ref = w * np.where(source, 2 * 0.8 * np.where(miss, 0.7, 1.0), np.where(miss, 4.0, 1.0))
    out = transfer_update(torch.from_numpy(w), torch.from_numpy(miss), torch.from_numpy(source), eps, beta)
    np.testing.assert_allclose(out.numpy(), ref / ref.sum(), rtol=1e-12)


def test_a_stump_that_fails_the_target_is_skipped_and_the_source_weights_shrink(monkeypatch: pytest.MonkeyPatch) -> None:
    """Many source positives choose a stump that only they pass: once the target weights are balanced its target
    error reaches 1/2, it is not kept, and the source weights shrink until a stump of the target's is chosen (the
    numpy reference on the same hand-made feature matrix; without the shrinking the same stump is chosen forever)."""
    import synthaug.detectors.adaboost as ada

    n_real, n_src, n_neg = 4, 40, 20
    y = np.r_[np.ones(n_real + n_src), np.zeros(n_neg)]
    source = np.r_[np.zeros(n_real), np.ones(n_src), np.zeros(n_neg)].astype(bool)
    rng = np.random.default_rng(0)
    f = np.stack([source.astype(float),                                        # passes the source positives only
                  np.r_[np.ones(n_real), np.zeros(n_src), np.ones(2), np.zeros(n_neg - 2)],  # real + 2 negatives
                  rng.uniform(size=len(y))], 1)
    monkeypatch.setattr(ada, "_features_chunked", lambda *a, **k: torch.from_numpy(f))
    pos, neg = toy_patches(n_real + n_src, n_neg, seed=1)
    det = train_adaboost(pos, neg, n_rounds=6, candidates=3, seed=0, source_positives=n_src)
    chosen, alphas = _np_tradaboost(f, y, source, 6)
    assert len(chosen) < 6  # the reference skipped a round
    rects, orients = exhaustive_candidates(40, 4, step=4, min_size=4)
    pick = torch.randperm(len(rects), generator=torch.Generator().manual_seed(0))[:3].sort().values
    assert det.learners.rects.tolist() == rects[pick][chosen].tolist()
    np.testing.assert_allclose(det.alphas.numpy(), alphas, rtol=1e-4)
