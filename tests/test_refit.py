"""Synthetic patches in Lightning training and the d_CNN refit callback."""

import json
from collections import Counter

import lightning as L
import numpy as np
import pytest
import torch

from synthaug.data.procedural import sky_backgrounds
from synthaug.data.seedset import write_seedset
from synthaug.detectors.lightning_module import PatchDetectorModule
from synthaug.fit.refit import CNNDistanceRefit, SyntheticEpochs, SyntheticPatchDataModule
from synthaug.params import CaptureParams


def tiny_seedset(tmp_path, n=6):
    """A 6-seed set of 40x40 sky patches with a dark bar (+ 12 negatives), written under ``tmp_path/seeds``."""
    bgs = sky_backgrounds(n, (40, 40), seed=0)
    patches = bgs.copy()
    patches[:, 16:24, 10:30] = 30
    frames = sky_backgrounds(n, (64, 64), seed=1)
    path = tmp_path / "seeds"
    write_seedset(path, patches=patches, backgrounds=bgs, boxes=[[0, 0, 20, 8]] * n, centres=[[20, 20]] * n,
                  crops=[[20, 20, 40]] * n, records=[{"video": "v"}] * n, frames=list(frames),
                  background_frames=list(frames), negatives=sky_backgrounds(12, (40, 40), seed=2),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    return path


_seeds = tiny_seedset


def test_datamodule_mixes_synthetic_patches(tmp_path):
    dm = SyntheticPatchDataModule(str(_seeds(tmp_path)), synthetic_per_real=3, step_deg=30, sprite_size=48,
                                  val_fraction=0.0, batch_size=8)
    dm.setup("fit")
    assert len(dm.synthetic) == 18
    n_real_pos, n_neg = 6, 12 + 6
    assert len(dm.train_set) == 2 * (n_real_pos + n_neg) + 18  # flipped copies of the real ones
    x, y = next(iter(dm.train_dataloader()))
    assert x.shape == (8, 1, 40, 40) and y.dtype == torch.float32


def test_datamodule_gives_the_cnn_familys_synthetic_defaults(tmp_path):
    """The Lightning path trains the CNN, so its synthetic stream is the one ``synthaug train`` gives the CNN: the
    fit's blurs left out and each object on another seed's background; each item equals the item of a
    SyntheticObjectDataset built with those options explicitly, and the paper's stream is one argument away."""
    from synthaug.data.seedset import SeedSet
    from synthaug.data.synthetic import SyntheticObjectDataset
    from synthaug.detectors.video_training import FAMILY_BACKGROUND_SAMPLING, FAMILY_EFFECTS_OFF

    seeds = _seeds(tmp_path)
    fit = tmp_path / "fit.json"
    CaptureParams.sample(6, generator=torch.Generator().manual_seed(4)).save(fit)
    kept = [e for e in CaptureParams.load(fit).effects if e not in FAMILY_EFFECTS_OFF["cnn"]]
    assert kept and len(kept) < len(CaptureParams.load(fit).effects)
    options = {"synthetic_per_real": 2, "step_deg": 30, "sprite_size": 48, "val_fraction": 0.0, "seed": 3}
    ss = SeedSet.load(seeds)

    def stream(**kwargs):
        return SyntheticObjectDataset("quadcopter", ss, fit, length=12, patch_size=40, negative_fraction=0.0, seed=3,
                                      render={"step_deg": 30, "sprite_size": 48}, **kwargs)

    def items(ds):
        return torch.stack([ds[i][0] for i in range(len(ds))])

    for dm_kwargs, ref_kwargs in (({}, {"effects": kept, "background_sampling": FAMILY_BACKGROUND_SAMPLING["cnn"]}),
                                  ({"effects_off": [], "background_sampling": "seed"}, {})):
        dm = SyntheticPatchDataModule(str(seeds), params=str(fit), **options, **dm_kwargs)
        dm.setup("fit")
        ref = stream(**ref_kwargs)
        assert dm.synthetic.effects == ref.effects and dm.synthetic.background_sampling == ref.background_sampling
        torch.testing.assert_close(items(dm.synthetic), items(ref), rtol=0, atol=0)
    paper, default = (SyntheticPatchDataModule(str(seeds), params=str(fit), **options, **kw)
                      for kw in ({"effects_off": [], "background_sampling": "seed"}, {}))
    paper.setup("fit")
    default.setup("fit")
    assert not torch.equal(items(paper.synthetic), items(default.synthetic))
    # sampled Θ (no fit) carries the paper's effects, and the family's blurs are left out of those too
    sampled = SyntheticPatchDataModule(str(seeds), **options)
    sampled.setup("fit")
    assert not set(sampled.synthetic.effects) & set(FAMILY_EFFECTS_OFF["cnn"]) and sampled.synthetic.effects
    one = SyntheticPatchDataModule(str(seeds), params=str(fit), effects_off="motion_blur", **options)  # a name
    one.setup("fit")
    assert one.synthetic.effects == tuple(e for e in CaptureParams.load(fit).effects if e != "motion_blur")
    with pytest.raises(ValueError, match="effects_off"):
        SyntheticPatchDataModule(str(seeds), params=str(fit), effects_off=["vignetting"], **options).setup("fit")
    with pytest.raises(ValueError, match="background_sampling"):
        SyntheticPatchDataModule(str(seeds), background_sampling="video", **options)


@pytest.mark.slow
def test_refit_callback_updates_the_synthetic_stream(tmp_path):
    seeds = _seeds(tmp_path)
    dm = SyntheticPatchDataModule(str(seeds), synthetic_per_real=2, step_deg=30, sprite_size=48, batch_size=16,
                                  val_fraction=0.0)
    refit = CNNDistanceRefit(every_n_epochs=1, budget=40)
    trainer = L.Trainer(max_epochs=2, accelerator="cpu", logger=False, enable_checkpointing=False,
                        enable_progress_bar=False, enable_model_summary=False, default_root_dir=tmp_path,
                        callbacks=[SyntheticEpochs(), refit])
    model = PatchDetectorModule(channels=(4, 8, 8, 8))
    assert dm.synthetic is None  # the stream is made in setup, which runs inside fit
    start = _StartParams()
    trainer.callbacks.append(start)
    trainer.fit(model, datamodule=dm)
    assert start.theta is not None  # the stream's Θ when training began (setup had run)
    assert len(refit.history) == 1  # after epoch 0 (none after the last epoch)
    out = refit.history[0]["file"]
    doc = json.loads(open(out).read())
    assert doc["metadata"]["config"]["distance"] == "cnn" and len(doc["rows"]) == 6
    torch.testing.assert_close(dm.synthetic.params.to_vector(), CaptureParams.load(out).to_vector())
    assert not torch.equal(dm.synthetic.params.to_vector(), start.theta)  # the refit replaced Θ
    assert dm.synthetic.seed_scales is not None


class _StartParams(L.Callback):
    """Keeps the synthetic stream's Θ as training starts (after the data module's setup)."""

    theta: torch.Tensor | None = None

    def on_fit_start(self, trainer, pl_module):
        params = trainer.datamodule.synthetic.params
        self.theta = None if params is None else params.to_vector().clone()


class _Recorder(PatchDetectorModule):
    """Keeps every training batch's patches, per epoch."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.seen: dict[int, list[torch.Tensor]] = {}

    def training_step(self, batch, batch_idx):
        self.seen.setdefault(self.current_epoch, []).append(batch[0].detach().clone())
        return super().training_step(batch, batch_idx)


def _keys(batches):
    # one key per item, independent of the shuffle order
    return sorted(round(float(v), 3) for v in torch.cat(batches).flatten(1).sum(1))


@pytest.mark.parametrize("workers", [0, 2])
def test_new_synthetic_poses_every_epoch(tmp_path, workers):
    """The DataLoader workers see the epoch that SyntheticEpochs sets (they are re-created every epoch)."""
    dm = SyntheticPatchDataModule(str(tiny_seedset(tmp_path)), synthetic_per_real=3, step_deg=30, sprite_size=48,
                                  val_fraction=0.0, batch_size=16, num_workers=workers)
    model = _Recorder(channels=(4, 8, 8, 8))
    trainer = L.Trainer(max_epochs=3, accelerator="cpu", logger=False, enable_checkpointing=False,
                        enable_progress_bar=False, enable_model_summary=False, default_root_dir=tmp_path,
                        callbacks=[SyntheticEpochs()])
    trainer.fit(model, datamodule=dm)
    k = [_keys(model.seen[e]) for e in range(3)]
    n_real, n_syn = 2 * (6 + 12 + 6), 18
    assert all(len(ki) == n_real + n_syn for ki in k)
    for a, b in ((0, 1), (1, 2)):
        common = sum((Counter(k[a]) & Counter(k[b])).values())
        assert n_real <= common < n_real + n_syn // 2, (a, b, common)  # the real items repeat, the synthetic ones not
    assert dm.train_dataloader().persistent_workers is False
    # and an epoch's items are a function of the epoch: the stream replays epoch 1 exactly
    dm.synthetic.set_epoch(1)
    replay = [dm.train_set[i][0] for i in range(len(dm.train_set))]
    assert _keys([torch.stack(replay)]) == k[1]


def test_refit_with_network_is_fit_seedset_with_a_frozen_copy_of_the_network(tmp_path):
    """The one d_CNN refit (the callback's and the mining rounds'): the same file as ``fit_seedset`` given the
    network as the ``cnn`` distance, the given options kept but the distance, the caller's network untouched."""
    from synthaug.detectors.cnn import PatchCNN
    from synthaug.distances.cnn import CNNDistance
    from synthaug.fit.config import FitConfig
    from synthaug.fit.refit import refit_with_network
    from synthaug.fit.run import fit_seedset

    seeds = _seeds(tmp_path)
    net = PatchCNN((4, 8, 8, 8), window=40, generator=torch.Generator().manual_seed(3)).train()
    before = {k: v.clone() for k, v in net.state_dict().items()}
    cfg = FitConfig(distance="hog", budget=30, step_deg=30.0, sprite_size=48, init="uniform", seed=5,
                    effects=("boundary_blur", "object_noise"))
    out = refit_with_network(net, seeds, "quadcopter", tmp_path / "refit.json", cfg)
    assert net.training and all(p.requires_grad for p in net.parameters())  # the caller's network is not frozen
    assert all(torch.equal(before[k], v) for k, v in net.state_dict().items())
    ref = fit_seedset(seeds, "quadcopter", tmp_path / "direct.json",
                      FitConfig(distance="cnn", budget=30, step_deg=30.0, sprite_size=48, init="uniform", seed=5,
                                effects=("boundary_blur", "object_noise")),
                      distance=CNNDistance(PatchCNN((4, 8, 8, 8), window=40,
                                                    generator=torch.Generator().manual_seed(3))))
    got, ref_doc = json.loads(out.read_text()), json.loads(ref.read_text())
    assert got["rows"] == ref_doc["rows"]
    assert got["metadata"]["config"] == ref_doc["metadata"]["config"]
    assert got["metadata"]["config"]["distance"] == "cnn" and got["metadata"]["config"]["seed"] == 5
    assert tuple(CaptureParams.load(out).effects) == ("boundary_blur", "object_noise")


def test_fit_config_reads_back_from_a_fit_files_metadata():
    """``config_from_json`` inverts what a fit file records (``_cfg_json``), tuples and the bounds included; a field
    FitConfig does not have is refused by name."""
    from synthaug.fit.config import FitConfig, _cfg_json, config_from_json

    for cfg in (FitConfig(), FitConfig(distance="cnn", effects=("motion_blur", "object_noise"), object_noise="measured",
                                       bounds={"sigma_n": (0.0, 0.05)}, scale_range=(0.5, 1.5), budget=99)):
        assert config_from_json(json.loads(json.dumps(_cfg_json(cfg)))) == cfg
    with pytest.raises(ValueError, match="'colour'"):
        config_from_json({**_cfg_json(FitConfig()), "colour": True})
