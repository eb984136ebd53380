"""``python train/fit.py --config configs/cnn_tiny.yaml``: resolved config, checkpoints, exported detector."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import torch
import yaml

REPO = Path(__file__).resolve().parents[1]


def run_fit(tmp_path: Path, *extra: str, timeout: int = 240, subcommand: tuple[str, ...] = ()) -> Path:
    """Run train/fit.py on the tiny config into ``tmp_path``; return the run's log folder."""
    cmd = [sys.executable, str(REPO / "train" / "fit.py"), *subcommand, "--config", str(REPO / "configs" / "cnn_tiny.yaml"),
           "--trainer.default_root_dir", str(tmp_path), "--trainer.logger.init_args.save_dir", str(tmp_path), *extra]
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=timeout, env=env)
    assert proc.returncode == 0, f"fit.py failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}"
    runs = sorted(tmp_path.glob("lightning_logs/version_*"))
    assert len(runs) == 1, list(tmp_path.rglob("*"))
    return runs[0]


@pytest.mark.slow
def test_fit_tiny_config(tmp_path: Path) -> None:
    run = run_fit(tmp_path)
    # the resolved configuration is saved with the run
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["model"]["channels"] == [8, 16, 32, 64] and cfg["data"]["generated_positives"] == 150
    assert cfg["trainer"]["max_epochs"] == 2 and "lr" in cfg["model"]
    # the Lightning checkpoint loads with weights_only=True and holds plain hyper-parameters
    (ckpt,) = run.glob("checkpoints/*.ckpt")
    state = torch.load(ckpt, map_location="cpu", weights_only=True)
    assert state["hyper_parameters"]["channels"] == [8, 16, 32, 64]
    assert state["epoch"] == 1
    # validation accuracy logged, and the toy task is learned
    metrics = (run / "metrics.csv").read_text().splitlines()
    header = metrics[0].split(",")
    last_val = [line.split(",") for line in metrics[1:] if line.split(",")[header.index("val_acc")]][-1]
    assert float(last_val[header.index("val_acc")]) > 0.9
    # the exported detector equals the checkpoint's network
    from synthaug.detectors.base import load_detector
    from synthaug.detectors.cnn import CNNDetector, load_patch_cnn
    from synthaug.detectors.lightning_module import export_detector

    det = load_detector(run / "detector.pt")
    assert isinstance(det, CNNDetector)
    from_ckpt = CNNDetector(load_patch_cnn(ckpt))
    x = torch.rand(5, 1, 40, 40, generator=torch.Generator().manual_seed(0))
    torch.testing.assert_close(det.score_patches(x), from_ckpt.score_patches(x))
    exported = export_detector(ckpt, tmp_path / "exported.pt")
    torch.testing.assert_close(load_detector(exported).score_patches(x), det.score_patches(x))
    # a corrupt checkpoint gives a clear error naming the file
    bad = tmp_path / "bad.ckpt"
    bad.write_bytes(ckpt.read_bytes()[:1000])
    with pytest.raises(ValueError, match="bad.ckpt"):
        load_patch_cnn(bad)
    # a mismatched checkpoint (hyper-parameters say another width) too
    state["hyper_parameters"]["channels"] = [4, 16, 32, 64]
    torch.save(state, tmp_path / "mismatch.ckpt")
    with pytest.raises(ValueError, match=r"do not match PatchCNN\(channels=\[4, 16, 32, 64\]"):
        load_patch_cnn(tmp_path / "mismatch.ckpt")


@pytest.mark.slow
def test_explicit_fit_subcommand_and_overrides(tmp_path: Path) -> None:
    run = run_fit(tmp_path, "--trainer.max_epochs", "1", "--data.generated_positives", "40",
                  "--data.generated_negatives", "40", "--model.channels", "[4, 8, 8, 16]", subcommand=("fit",))
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["model"]["channels"] == [4, 8, 8, 16] and cfg["trainer"]["max_epochs"] == 1
    from synthaug.detectors.base import load_detector

    assert load_detector(run / "detector.pt").net.channels == (4, 8, 8, 16)


def test_datamodule_same_items_with_0_and_2_workers() -> None:
    from synthaug.detectors.lightning_module import PatchDataModule

    def batches(workers: int) -> list[torch.Tensor]:
        dm = PatchDataModule(generated_positives=12, generated_negatives=12, batch_size=8, num_workers=workers, seed=3)
        dm.setup("fit")
        return [torch.cat([x.flatten(1), y[:, None]], 1) for x, y in dm.train_dataloader()]

    a, b = batches(0), batches(2)
    assert len(a) == len(b) and all(torch.equal(p, q) for p, q in zip(a, b))


def test_datamodule_flip_split_and_errors() -> None:
    from synthaug.detectors.lightning_module import PatchDataModule, PatchDataset

    ds = PatchDataset(torch.arange(2 * 4 * 4.0).reshape(2, 1, 4, 4), torch.tensor([1.0, 0.0]))
    assert len(ds) == 4 and torch.equal(ds[1][0], ds[0][0].flip(-1)) and ds[3][1] == 0
    dm = PatchDataModule(generated_positives=10, generated_negatives=30, val_fraction=0.2)
    dm.setup()
    assert len(dm.val_set) == 8 and len(dm.train_set) == 2 * 32 and dm.negative_positive_ratio == 3.0
    with pytest.raises(ValueError, match="no data"):
        PatchDataModule()
    with pytest.raises(ValueError, match="val_fraction"):
        PatchDataModule(generated_positives=2, val_fraction=1.0)


def test_seed_dir_datamodule(tmp_path: Path) -> None:
    np = pytest.importorskip("numpy")
    from synthaug.data.seedset import write_seedset
    from synthaug.detectors.lightning_module import PatchDataModule

    rng = np.random.default_rng(0)
    n = 5
    patches = rng.integers(0, 255, (n, 40, 40), dtype=np.uint8)
    frame = np.zeros((60, 80), np.uint8)
    write_seedset(tmp_path / "s", patches=patches, backgrounds=patches // 2, boxes=[[0, 0, 10, 10]] * n,
                  centres=[[5, 5]] * n, crops=[[5, 5, 14]] * n, records=[{"video": "v"}] * n,
                  frames=[frame] * n, background_frames=[frame] * n,
                  negatives=rng.integers(0, 255, (3, 40, 40), dtype=np.uint8),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    dm = PatchDataModule(seed_dir=str(tmp_path / "s"), val_fraction=0.0, flip=False)
    pos, neg = dm.load_patches()
    assert pos.shape == (5, 1, 40, 40) and neg.shape == (8, 1, 40, 40)
    torch.testing.assert_close(pos[:, 0], torch.from_numpy(patches).float() / 255)
