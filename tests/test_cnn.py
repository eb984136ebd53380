"""PatchCNN: fully convolutional scoring == per-crop scoring, d_CNN = eq. 6, checkpoints."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from synthaug.detectors.base import load_detector, save_detector
from synthaug.detectors.cnn import CNNDetector, PatchCNN, load_patch_cnn
from synthaug.detectors.lightning_module import train_patch_cnn
from synthaug.detectors.toy import toy_frame, toy_patches
from synthaug.distances import get_distance
from synthaug.distances.cnn import CNNDistance


def _net(seed: int = 0, channels=(8, 16, 32, 64)) -> PatchCNN:
    return PatchCNN(channels, generator=torch.Generator().manual_seed(seed))


def test_shapes_and_layers() -> None:
    net = _net()
    x = torch.rand(3, 1, 40, 40)
    acts = net.layer_activations(x)
    assert [tuple(a.shape[1:]) for a in acts] == [(8, 18, 18), (16, 8, 8), (32, 3, 3), (64, 1, 1), (1, 1, 1)]
    torch.testing.assert_close(net(x), acts[-1].flatten())
    assert net(x[:0]).shape == (0,)


@pytest.mark.parametrize("size", [(40, 40), (47, 55), (48, 96), (121, 163)])
def test_score_map_equals_scoring_every_crop(size: tuple[int, int]) -> None:
    det = CNNDetector(_net(1))
    img = torch.rand(1, 1, *size, generator=torch.Generator().manual_seed(2))
    dense = det.score_map(img)
    assert dense.shape == ((size[0] - 40) // 8 + 1, (size[1] - 40) // 8 + 1)
    crops = torch.nn.functional.unfold(img, 40, stride=8)[0].T.reshape(-1, 1, 40, 40)
    torch.testing.assert_close(dense, det.score_patches(crops).reshape(dense.shape), atol=1e-4, rtol=1e-4)
    assert det.score_map(torch.rand(1, 1, 39, 100)).shape == (0, 8)


def test_seeded_init_is_reproducible() -> None:
    a, b, c = _net(5), _net(5), _net(6)
    assert all(torch.equal(p, q) for p, q in zip(a.parameters(), b.parameters()))
    assert not torch.equal(a.conv1.weight, c.conv1.weight)


def test_cnn_distance_is_eq6() -> None:
    net = _net(3)
    d = CNNDistance(net)
    real = torch.rand(1, 1, 40, 40, generator=torch.Generator().manual_seed(4))
    syn = torch.rand(5, 1, 40, 40, generator=torch.Generator().manual_seed(5))
    # reference: numpy sum over neurons of layers 2..5, written out layer by layer
    with torch.no_grad():
        ar = [a.numpy().astype(np.float64) for a in net.layer_activations(real)]
        as_ = [a.numpy().astype(np.float64) for a in net.layer_activations(syn)]
    ref = np.sqrt(sum(((ar[n] - as_[n]) ** 2).reshape(5, -1).sum(1) for n in range(1, 5)))
    np.testing.assert_allclose(d(real, syn).detach().numpy(), ref, rtol=1e-5)
    # layer 1 is excluded: a distance over layers 1..N is strictly larger here
    assert (CNNDistance(net, first_layer=1)(real, syn) > d(real, syn)).all()


def test_cnn_distance_sources_and_frozen_net(tmp_path) -> None:
    pos, neg = toy_patches(40, 40, seed=0)
    d = get_distance("cnn", positives=pos, negatives=neg, epochs=1)
    assert not any(p.requires_grad for p in d.net.parameters())
    path = save_detector(CNNDetector(d.net), tmp_path / "cnn.pt")
    d2 = get_distance("cnn", checkpoint=path)
    x = torch.rand(3, 1, 40, 40)
    torch.testing.assert_close(d2(x[:1], x), d(x[:1], x))
    d.train()
    assert not d.net.training
    with pytest.raises(ValueError, match="exactly one"):
        get_distance("cnn")
    with pytest.raises(ValueError, match="exactly one"):
        get_distance("cnn", net=_net(), checkpoint=path)
    with pytest.raises(ValueError, match=r"\(B, 1, 40, 40\)"):
        d(torch.rand(1, 1, 32, 32), torch.rand(2, 1, 32, 32))


def test_train_patch_cnn_learns_toy_task() -> None:
    pos, neg = toy_patches(80, 160, seed=0)
    net = train_patch_cnn(pos, neg, epochs=4, seed=0)
    tp, tn = toy_patches(100, 100, seed=77)
    with torch.no_grad():
        s = net(torch.cat([tp, tn]))
    acc = ((s[:100] > 0).float().mean() + (s[100:] <= 0).float().mean()) / 2
    assert acc > 0.9, acc


def test_detect_multiscale_runs() -> None:
    from synthaug.detectors.sliding import detect_multiscale

    frame, _ = toy_frame(200, 240, n_objects=2, seed=1)
    dets = detect_multiscale(CNNDetector(_net()), frame, scales=(1.0, 0.8), max_detections=5)
    assert dets.shape == (5, 5)
    assert (dets[:, 2:4] > 0).all() and (dets[:-1, 4] >= dets[1:, 4]).all()


def test_checkpoint_roundtrip_mismatch_and_corrupt(tmp_path) -> None:
    det = CNNDetector(_net(7))
    path = save_detector(det, tmp_path / "cnn.pt")
    back = load_detector(path)
    x = torch.rand(4, 1, 40, 40)
    torch.testing.assert_close(back.score_patches(x), det.score_patches(x))
    # weights_only loading works on the raw file
    raw = torch.load(path, weights_only=True)
    # mismatched: the config says wider layers than the weights have
    raw["state"]["config"]["channels"] = [16, 16, 32, 64]
    torch.save(raw, tmp_path / "mismatch.pt")
    with pytest.raises(ValueError, match=r"mismatch\.pt.*do not match PatchCNN\(channels=\[16, 16, 32, 64\]"):
        load_detector(tmp_path / "mismatch.pt")
    (tmp_path / "corrupt.pt").write_bytes(path.read_bytes()[: len(path.read_bytes()) // 2])
    with pytest.raises(ValueError, match="corrupt.pt"):
        load_detector(tmp_path / "corrupt.pt")
    with pytest.raises(ValueError, match="corrupt.pt"):
        load_patch_cnn(tmp_path / "corrupt.pt")
    with pytest.raises(FileNotFoundError):
        load_patch_cnn(tmp_path / "missing.pt")
    torch.save({"something": 1}, tmp_path / "other.pt")
    with pytest.raises(ValueError, match="neither"):
        load_patch_cnn(tmp_path / "other.pt")


@pytest.mark.parametrize(
    "kwargs, match",
    [({"channels": (8, 16, 32)}, "channels"), ({"channels": (8, 0, 32, 64)}, "channels"),
     ({"window": 41}, "pool exactly"), ({"window": 8}, "window")],
)
def test_bad_construction(kwargs, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        PatchCNN(**kwargs)


def test_forward_rejects_wrong_patch_size() -> None:
    with pytest.raises(ValueError, match="forward expects"):
        _net()(torch.rand(2, 1, 48, 48))
    with pytest.raises(ValueError, match="PatchCNN"):
        CNNDetector("not a net")  # type: ignore[arg-type]


@pytest.mark.parametrize("size", [(8, 8), (9, 12), (7, 5)])
def test_fast_max_pool_matches_torch(size: tuple[int, int]) -> None:
    from synthaug.detectors.cnn import _max_pool2

    x = torch.randn(2, 3, *size, generator=torch.Generator().manual_seed(0))
    assert torch.equal(_max_pool2(x), torch.nn.functional.max_pool2d(x, 2))
    # gradients reach the input through the pooling (used by the differentiable cnn distance)
    xr = x.clone().requires_grad_(True)
    _max_pool2(xr).sum().backward()
    assert xr.grad.sum().item() == pytest.approx(2 * 3 * (size[0] // 2) * (size[1] // 2))


def test_one_training_loop_for_experiments_and_distance(monkeypatch) -> None:
    """train_detector("cnn") and train_patch_cnn both train PatchDetectorModule under lightning.Trainer."""
    from synthaug.detectors.lightning_module import PatchDetectorModule, fit_patch_detector
    from synthaug.detectors.training import TrainOptions, train_detector

    steps = []
    original = PatchDetectorModule.training_step

    def spy(self, batch, batch_idx):
        steps.append(len(batch[1]))
        return original(self, batch, batch_idx)

    monkeypatch.setattr(PatchDetectorModule, "training_step", spy)
    pos, neg = toy_patches(30, 50, seed=1)
    options = TrainOptions(cnn_epochs=2, cnn_batch_size=32)
    det = train_detector("cnn", pos, neg, 4, box_in_window=(5, 5, 30, 30), options=options)
    # 2 passes over the 80 patches = 1 epoch of the flip-doubled set, batches of 32: 5 steps
    assert isinstance(det, CNNDetector) and det.box_in_window == (5.0, 5.0, 30.0, 30.0)
    assert steps == [32] * 5 and not det.net.training
    # the same seed gives the same weights: the experiments' detector is the module trained directly
    module = fit_patch_detector(pos, neg, epochs=2, batch_size=32, seed=4)
    again = train_detector("cnn", pos, neg, 4, options=options)
    weights = [m.state_dict().values() for m in (det.net, module.net, again.net)]
    for a, b, c in zip(*weights):
        assert torch.equal(a, b) and torch.equal(a, c)
    other = train_detector("cnn", pos, neg, 5, options=options)
    assert not torch.equal(other.net.conv1.weight, det.net.conv1.weight)
    # train_patch_cnn (the d_CNN distance, benchmarks) is the same loop
    steps.clear()
    net = train_patch_cnn(pos, neg, epochs=2, batch_size=32, seed=4)
    assert len(steps) == 5 and torch.equal(net.conv1.weight, det.net.conv1.weight)
    # an odd number of passes stops inside the second epoch: 3 x 80 / 32 -> 8 steps
    steps.clear()
    train_patch_cnn(pos, neg, epochs=3, batch_size=32, seed=4)
    assert len(steps) == 8
    # no global RNG is drawn from: training leaves torch's default generator where it was
    state = torch.get_rng_state()
    train_patch_cnn(pos, neg, epochs=1, batch_size=32, seed=4)
    assert torch.equal(state, torch.get_rng_state())


def test_fit_patch_detector_validation_and_errors() -> None:
    from synthaug.detectors.lightning_module import PatchDataModule, fit_patch_detector

    pos, neg = toy_patches(20, 40, seed=0)
    module = fit_patch_detector(pos, neg, epochs=2, batch_size=16, val_fraction=0.25)
    assert {"val_loss", "val_acc", "train_loss"} <= set(module.trainer.callback_metrics)
    dm = PatchDataModule.from_tensors(pos, neg, val_fraction=0.25, batch_size=16)
    dm.setup("fit")
    assert len(dm.val_set) == 15 and len(dm.train_set) == 2 * 45 and dm.negative_positive_ratio == 2.0
    with pytest.raises(ValueError, match="non-empty"):
        fit_patch_detector(pos[:0], neg)
    with pytest.raises(ValueError, match="epochs"):
        fit_patch_detector(pos, neg, epochs=0)
    with pytest.raises(ValueError, match="one size"):
        PatchDataModule.from_tensors(pos, neg[..., :32, :32])


def test_shift_patches_is_a_reflect_pad_and_crop_of_the_flagged_patches_only():
    import numpy as np

    from synthaug.detectors.lightning_module import shift_patches

    x = torch.rand(5, 1, 10, 10, generator=torch.Generator().manual_seed(0))
    before = x.clone()
    which = torch.tensor([True, False, True, True, False])
    out = shift_patches(x, which, 2, generator=torch.Generator().manual_seed(4))
    offsets = torch.randint(0, 5, (3, 2), generator=torch.Generator().manual_seed(4)).tolist()  # the same draws
    assert torch.equal(x, before)  # input untouched
    for k, i in enumerate([0, 2, 3]):
        dy, dx = offsets[k]
        ref = np.pad(x[i, 0].numpy(), 2, mode="reflect")[dy:dy + 10, dx:dx + 10]
        np.testing.assert_array_equal(out[i, 0].numpy(), ref)
    assert torch.equal(out[1], x[1]) and torch.equal(out[4], x[4])
    assert torch.equal(shift_patches(x, which, 0, generator=torch.Generator()), x)


def test_cnn_training_with_shift_is_deterministic_and_differs_from_without():
    from synthaug.detectors.lightning_module import fit_patch_detector
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(16, 32, seed=0)
    a = fit_patch_detector(pos, neg, epochs=2, batch_size=16, seed=0, shift=4).net.state_dict()
    b = fit_patch_detector(pos, neg, epochs=2, batch_size=16, seed=0, shift=4).net.state_dict()
    c = fit_patch_detector(pos, neg, epochs=2, batch_size=16, seed=0, shift=0).net.state_dict()
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert not all(torch.equal(a[k], c[k]) for k in a)


# ----------------------------------------------------------------- per-positive loss weights (--synthetic-share)
def _step_loss_and_grad(module, batch):
    """``PatchDetectorModule._step``'s loss and its gradient over the network's parameters (no trainer: the
    module's ``self.log`` only warns)."""
    import warnings

    module.zero_grad()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loss = module._step(batch, "train")
    loss.backward()
    return loss.detach(), [p.grad.detach().clone() for p in module.net.parameters()]


def test_cnn_loss_weight_2_is_the_sample_twice_and_0_is_leaving_it_out() -> None:
    from synthaug.detectors.lightning_module import PatchDetectorModule

    x = torch.rand(6, 1, 40, 40, generator=torch.Generator().manual_seed(3))
    y = torch.tensor([1.0, 1.0, 1.0, 0.0, 1.0, 0.0])
    w = torch.tensor([1.0, 2.0, 1.0, 1.0, 0.0, 1.0])  # sample 1 counts twice, sample 4 not at all
    module = PatchDetectorModule(pos_weight=3.0, init_seed=1)
    loss_w, grad_w = _step_loss_and_grad(module, (x, y, w))
    # by hand: the mean over the batch of w_i * BCE_i, the positives' terms times pos_weight
    z = module.net(x).detach()
    by_hand = -(3.0 * y * torch.log(torch.sigmoid(z)) + (1 - y) * torch.log(1 - torch.sigmoid(z)))
    torch.testing.assert_close(loss_w, (w * by_hand).sum() / 6)
    ref = torch.nn.functional.binary_cross_entropy_with_logits(z, y, pos_weight=torch.tensor(3.0), reduction="none")
    torch.testing.assert_close(by_hand, ref)
    # the same batch with sample 1 repeated and sample 4 dropped, unweighted: the same sum, so the same gradient
    keep = [0, 1, 1, 2, 3, 5]
    loss_rep, grad_rep = _step_loss_and_grad(module, (x[keep], y[keep]))
    torch.testing.assert_close(loss_rep * len(keep), loss_w * 6)
    for a, b in zip(grad_rep, grad_w):
        torch.testing.assert_close(a * len(keep), b * 6, rtol=1e-4, atol=1e-5)  # float32 sums
    # weight 0 alone: the gradient of the batch without that sample
    w0 = torch.tensor([1.0, 1.0, 1.0, 1.0, 0.0, 1.0])
    loss_0, grad_0 = _step_loss_and_grad(module, (x, y, w0))
    rest = [0, 1, 2, 3, 5]
    loss_drop, grad_drop = _step_loss_and_grad(module, (x[rest], y[rest]))
    torch.testing.assert_close(loss_drop * 5, loss_0 * 6)
    for a, b in zip(grad_drop, grad_0):
        torch.testing.assert_close(a * 5, b * 6, rtol=1e-4, atol=1e-5)
    # the shift augmentation passes the weights on
    shifted = PatchDetectorModule(pos_weight=3.0, init_seed=1, shift=2)
    seen = []
    shifted._step = lambda batch, stage: seen.append(batch) or torch.zeros(())
    shifted.training_step((x, y, w), 0)
    assert len(seen[0]) == 3 and torch.equal(seen[0][2], w)


def _identify(x, originals):
    """Index of the original patch ``x`` is, and whether it is the mirror image."""
    for j, o in enumerate(originals):
        if torch.equal(x, o):
            return j, False
        if torch.equal(x, o.flip(-1)):
            return j, True
    raise AssertionError("patch not found")


def test_cnn_positive_weights_survive_the_flip_doubling_and_the_split() -> None:
    from synthaug.detectors.lightning_module import PatchDataModule

    g = torch.Generator().manual_seed(0)
    pos, neg = torch.rand(10, 1, 40, 40, generator=g), torch.rand(12, 1, 40, 40, generator=g)
    w = torch.linspace(0.1, 2.8, 10)  # one distinct weight per positive
    dm = PatchDataModule.from_tensors(pos, neg, positive_weights=w, val_fraction=0.3, batch_size=4, seed=3)
    dm.setup("fit")
    seen_train, seen_val = {}, {}
    for ds, seen in ((dm.train_set, seen_train), (dm.val_set, seen_val)):
        for i in range(len(ds)):
            x, y, wi = ds[i]
            if y == 1:
                j, mirrored = _identify(x, pos)
                assert float(wi) == pytest.approx(float(w[j])), (j, mirrored)  # a mirror keeps its patch's weight
                seen.setdefault(j, []).append(mirrored)
            else:
                _identify(x, neg)
                assert float(wi) == 1.0  # negatives weigh 1
    # every positive is in exactly one part: twice in training (itself and its mirror), once in validation
    assert not set(seen_train) & set(seen_val)
    assert set(seen_train) | set(seen_val) == set(range(10)) and len(seen_val) == 3
    assert all(sorted(m) == [False, True] for m in seen_train.values())
    assert all(m == [False] for m in seen_val.values())
    assert dm.negative_positive_ratio == 1.2  # the class balance stays by count
    # batches carry the weights; without positive_weights the items stay (patch, label)
    xb, yb, wb = next(iter(dm.train_dataloader()))
    assert xb.shape == (4, 1, 40, 40) and wb.shape == (4,) and wb.dtype == torch.float32
    plain = PatchDataModule.from_tensors(pos, neg, val_fraction=0.3, batch_size=4, seed=3)
    plain.setup("fit")
    assert len(plain.train_set[0]) == 2 and len(next(iter(plain.train_dataloader()))) == 2
    with pytest.raises(ValueError, match="one per positive"):
        PatchDataModule.from_tensors(pos, neg, positive_weights=torch.ones(9))
    with pytest.raises(ValueError, match=">= 0"):
        PatchDataModule.from_tensors(pos, neg, positive_weights=-torch.ones(10))


def test_cnn_default_training_is_unchanged_by_the_weights_option(monkeypatch) -> None:
    """No weights: the loss is the unweighted BCE of before (pinned here as the old ``_step``), bit for bit; weights
    of 1 give the same network bit for bit; other weights another one."""
    from synthaug.detectors.lightning_module import PatchDetectorModule, fit_patch_detector

    pos, neg = toy_patches(24, 40, seed=2)
    default = fit_patch_detector(pos, neg, epochs=3, batch_size=16, seed=5, val_fraction=0.2).net.state_dict()
    ones = fit_patch_detector(pos, neg, epochs=3, batch_size=16, seed=5, val_fraction=0.2,
                              positive_weights=torch.ones(24)).net.state_dict()
    other = fit_patch_detector(pos, neg, epochs=3, batch_size=16, seed=5, val_fraction=0.2,
                               positive_weights=torch.linspace(0.2, 1.8, 24)).net.state_dict()

    def old_step(self, batch, stage):  # PatchDetectorModule._step before per-sample weights existed
        x, y = batch
        logits = self.net(x)
        loss = torch.nn.functional.binary_cross_entropy_with_logits(logits, y, pos_weight=self._pos_weight())
        acc = ((logits > 0).float() == y).float().mean()
        self.log(f"{stage}_loss", loss, prog_bar=True, sync_dist=stage != "train", batch_size=len(y))
        self.log(f"{stage}_acc", acc, prog_bar=stage != "train", sync_dist=stage != "train", batch_size=len(y))
        return loss

    monkeypatch.setattr(PatchDetectorModule, "_step", old_step)
    before = fit_patch_detector(pos, neg, epochs=3, batch_size=16, seed=5, val_fraction=0.2).net.state_dict()
    assert all(torch.equal(default[k], before[k]) for k in default)
    assert all(torch.equal(default[k], ones[k]) for k in default)
    assert not all(torch.equal(default[k], other[k]) for k in default)
