"""``python train/detector_tv.py``: a torchvision detector fine-tuned on real + synthetic frames through LightningCLI.

One in-process run of the tiny config (2 training steps on CPU, one validation batch) on a seed set written
here; the tests read what it left: finite losses, ``val_map_50``, the weights file, and that training moved
the parameters.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import math
import os
import sys
from pathlib import Path

import lightning as L
import numpy as np
import pytest
import torch
import yaml

REPO = Path(__file__).resolve().parents[1]
FRAME = (96, 128)  # (H, W) of the seed frames


def _load_script():
    name = "synthaug_train_detector_tv"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, REPO / "train" / "detector_tv.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # jsonargparse resolves the classes through their module
    spec.loader.exec_module(mod)
    return mod


def _write_seeds(path: Path, n: int = 4) -> Path:
    """Sky frames with a dark rectangle as the labelled object, one video per seed."""
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import crop_patch, write_seedset

    bg_frames = sky_backgrounds(n, FRAME, seed=5)
    frames, boxes, patches, bgs, crops = [], [], [], [], []
    for i in range(n):
        f = bg_frames[i].copy()
        x, y, w, h = 20 + 12 * i, 30 + 6 * i, 18, 10
        f[y:y + h, x:x + w] = 30
        p, c = crop_patch(f, box=(x, y, w, h), patch_size=40, object_fraction=0.7)
        b, _ = crop_patch(bg_frames[i], crop=c, patch_size=40)
        frames.append(f)
        boxes.append([x, y, w, h])
        patches.append(p)
        bgs.append(b)
        crops.append(c)
    return write_seedset(path, patches=np.stack(patches), backgrounds=np.stack(bgs), boxes=boxes,
                         centres=[[x + w / 2, y + h / 2] for x, y, w, h in boxes], crops=crops,
                         records=[{"video": f"v{i}", "frame": i} for i in range(n)], frames=frames,
                         background_frames=list(bg_frames), metadata={"patch_size": 40, "object_fraction": 0.7})


class _Record(L.Callback):
    """Test-side callback: the parameters before training and every step's loss."""

    def __init__(self) -> None:
        self.before: dict[str, torch.Tensor] = {}
        self.losses: list[float] = []

    def on_train_start(self, trainer, pl_module) -> None:
        self.before = {k: v.detach().clone() for k, v in pl_module.detector.state_dict().items()}

    def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx) -> None:
        self.losses.append(float(outputs["loss"]))


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """Two training steps + one validation batch of the tiny config, in this process (an epoch of 2 batches:
    validation runs at the end of an epoch, and max_steps alone stops the run mid-epoch without one)."""

    tmp = tmp_path_factory.mktemp("detector_tv")
    seeds = _write_seeds(tmp / "seeds")
    script = _load_script()
    record = _Record()
    old = {k: os.environ.get(k) for k in ("PL_GLOBAL_SEED", "PL_SEED_WORKERS")}
    try:
        cli = script.main(["--config", str(REPO / "configs" / "detector_tv_tiny.yaml"),
                           "--trainer.default_root_dir", str(tmp), "--trainer.logger.init_args.save_dir", str(tmp),
                           "--data.seed_dir", str(seeds), "--data.params", "null",
                           "--trainer.max_steps", "2", "--trainer.limit_train_batches", "2",
                           "--trainer.limit_val_batches", "1"],
                          trainer_defaults={"callbacks": [record]})
    finally:  # LightningCLI's seed_everything exports these; keep them out of the other tests
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return cli, record, Path(cli.trainer.log_dir), seeds


@pytest.mark.slow
def test_two_steps_log_finite_losses_and_val_map(run) -> None:
    cli, record, log_dir, seeds = run
    assert cli.trainer.global_step == 2
    assert len(record.losses) == 2 and all(math.isfinite(v) and v > 0 for v in record.losses), record.losses
    dm = cli.datamodule
    assert len(dm.val_seeds) == 1 and len(dm.train_seeds) == 3  # val_fraction 0.3 of 4 one-video seeds
    assert len(dm.train_set) == 3 + 2 * 3  # real training frames + 2 synthetic per real
    from synthaug.data.synthetic import EpochSampler

    assert isinstance(cli.trainer.train_dataloader.sampler, EpochSampler)  # new synthetic poses every epoch
    m = cli.trainer.callback_metrics
    assert "val_map_50" in m and -1.0 <= float(m["val_map_50"]) <= 1.0
    rows = list(csv.DictReader((log_dir / "metrics.csv").open()))
    train = [float(r["train_loss"]) for r in rows if r.get("train_loss")]
    assert len(train) == 2 and all(math.isfinite(v) for v in train)
    assert [float(r["val_map_50"]) for r in rows if r.get("val_map_50")] == [pytest.approx(float(m["val_map_50"]))]
    cfg = yaml.safe_load((log_dir / "config.yaml").read_text())
    assert cfg["model"]["arch"] == "fasterrcnn_mobilenet_v3_large_320_fpn" and cfg["data"]["seed_dir"] == str(seeds)


def test_weights_file_loads_weights_only_and_predicts(run) -> None:
    cli, _, log_dir, seeds = run
    script = _load_script()
    state = torch.load(log_dir / "detector_tv.pt", weights_only=True)
    assert isinstance(state, dict) and all(isinstance(v, torch.Tensor) for v in state.values())
    arch = json.loads((log_dir / "detector_tv.json").read_text())
    assert arch == {"arch": "fasterrcnn_mobilenet_v3_large_320_fpn", "num_classes": 2, "min_size": 128,
                    "max_size": 160, "anchor_sizes": [16, 32, 64, 128, 256]}
    model = script.build_model(**arch)
    model.load_state_dict(state)
    model.eval()
    from synthaug.data.seedset import SeedSet

    frame = torch.from_numpy(SeedSet.load(seeds).frame(0)).float()[None] / 255.0  # gray (1, H, W)
    with torch.no_grad():
        (pred,) = model(script.to_model_input([frame]))
        (again,) = script.load_detector_tv(log_dir / "detector_tv.pt")(script.to_model_input([frame]))
    assert set(pred) == {"boxes", "scores", "labels"} and pred["boxes"].shape[1:] == (4,)
    assert torch.isfinite(pred["boxes"]).all() and len(pred["boxes"]) == len(pred["scores"])
    torch.testing.assert_close(pred["boxes"], again["boxes"])
    # the trained module's own detector predicts the same
    with torch.no_grad():
        (own,) = cli.model.eval()([frame])
    torch.testing.assert_close(pred["scores"], own["scores"])


def test_two_steps_change_the_parameters(run) -> None:
    cli, record, log_dir, _ = run
    after = torch.load(log_dir / "detector_tv.pt", weights_only=True)
    assert set(after) == set(record.before)
    changed = [k for k, v in record.before.items() if v.is_floating_point() and not torch.equal(v, after[k])]
    trainable = [k for k, p in cli.model.detector.named_parameters() if p.requires_grad]
    assert trainable and set(trainable) <= set(changed)  # every trainable weight moved (SGD + weight decay)
    assert any(k.startswith("roi_heads.box_predictor") for k in changed)


def test_ssdlite_and_options() -> None:
    """ssdlite builds with a fixed (W, H) input size and predicts on a gray frame; bad options fail early."""
    script = _load_script()
    m = script.build_model("ssdlite320_mobilenet_v3_large", min_size=96, max_size=128).eval()
    assert m.transform.fixed_size == (128, 96)
    with torch.no_grad():
        (pred,) = m(script.to_model_input([torch.rand(1, *FRAME)]))
    assert pred["boxes"].shape[1:] == (4,) and len(pred["boxes"]) <= 100
    with pytest.raises(ValueError, match="anchor_sizes"):
        script.build_model("ssdlite320_mobilenet_v3_large", anchor_sizes=[8, 16, 32, 64, 128])
    with pytest.raises(ValueError, match="5 positive sizes"):
        script.build_model(anchor_sizes=[16, 32])
    with pytest.raises(ValueError, match="arch"):
        script.build_model("yolo")
    assert script.video_split([{"video": "a"}] * 3, 0.5) == ([0, 1, 2], [])  # one video: nothing to hold out


def test_drone_config_parses() -> None:
    """The real-data config names existing arguments (parsed, not run: no data needed)."""
    script = _load_script()
    cfg = yaml.safe_load((REPO / "configs" / "detector_tv_drone.yaml").read_text())
    import inspect

    for section, cls in (("model", script.TorchvisionDetector), ("data", script.SyntheticFramesDataModule)):
        assert set(cfg[section]) <= set(inspect.signature(cls).parameters), section
    assert cfg["data"]["seed_dir"] == "data/halmstad/seedsets/drone_100"
    assert cfg["data"]["params"] == "fits/drone_100_hog.json"
    assert cfg["data"]["mesh"] == "../shared/data/meshes/quadcopter.glb"
