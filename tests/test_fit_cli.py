"""``python train/fit.py --config configs/<name>.yaml``: data module by class_path, resolved config, checkpoints,
exported detector."""

from __future__ import annotations

import importlib.util
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


def fit_main(tmp_path: Path, config: str, *extra: str):
    """``train/fit.py``'s ``main([...])`` in this process, logs under ``tmp_path``; returns the LightningCLI."""
    spec = importlib.util.spec_from_file_location("synthaug_train_fit", REPO / "train" / "fit.py")
    fit = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fit)
    return fit.main(["--config", str(REPO / "configs" / config), "--trainer.default_root_dir", str(tmp_path),
                     "--trainer.logger.init_args.save_dir", str(tmp_path), *extra])


@pytest.fixture
def _global_seed_env(monkeypatch):
    # LightningCLI's seed_everything exports PL_GLOBAL_SEED; keep it out of the other tests
    monkeypatch.setenv("PL_GLOBAL_SEED", "0")
    monkeypatch.setenv("PL_SEED_WORKERS", "0")


def _check_run(cli, tmp_path: Path, class_path: str) -> dict:
    from synthaug.detectors.base import load_detector
    from synthaug.detectors.cnn import CNNDetector

    run = Path(cli.trainer.log_dir)
    assert run.parent == tmp_path / "lightning_logs"
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["data"]["class_path"] == class_path
    det = load_detector(run / "detector.pt")
    assert isinstance(det, CNNDetector)
    x = torch.rand(3, 1, 40, 40, generator=torch.Generator().manual_seed(0))
    torch.testing.assert_close(det.score_patches(x), cli.model.to_detector().score_patches(x))
    return cfg


@pytest.mark.usefixtures("_global_seed_env")
def test_real_only_config_in_process(tmp_path: Path) -> None:
    from synthaug.detectors.lightning_module import PatchDataModule

    cli = fit_main(tmp_path, "cnn_tiny.yaml", "--trainer.max_epochs", "1", "--trainer.limit_train_batches", "3",
                   "--data.init_args.generated_positives", "80", "--data.init_args.generated_negatives", "80")
    assert type(cli.datamodule) is PatchDataModule and cli.trainer.global_step == 3
    cfg = _check_run(cli, tmp_path, "synthaug.detectors.lightning_module.PatchDataModule")
    assert cfg["data"]["init_args"]["generated_positives"] == 80


@pytest.mark.usefixtures("_global_seed_env")
def test_synthetic_config_in_process(tmp_path: Path) -> None:
    from test_refit import tiny_seedset

    from synthaug.fit.refit import SyntheticEpochs, SyntheticPatchDataModule

    seeds = tiny_seedset(tmp_path)
    cli = fit_main(tmp_path, "cnn_tiny_synthetic.yaml", "--data.init_args.seed_dir", str(seeds),
                   "--data.init_args.params", "null", "--trainer.max_epochs", "1",
                   "--trainer.limit_train_batches", "3", "--trainer.limit_val_batches", "2")
    dm = cli.datamodule
    assert isinstance(dm, SyntheticPatchDataModule) and dm.synthetic is not None and len(dm.synthetic) == 5 * 6
    assert cli.trainer.global_step == 3
    assert sum(isinstance(c, SyntheticEpochs) for c in cli.trainer.callbacks) == 1  # from the YAML, not doubled
    cfg = _check_run(cli, tmp_path, "synthaug.fit.refit.SyntheticPatchDataModule")
    assert cfg["data"]["init_args"]["seed_dir"] == str(seeds) and cfg["data"]["init_args"]["step_deg"] == 30.0
    assert [c["class_path"] for c in cfg["trainer"]["callbacks"]] == ["synthaug.fit.refit.SyntheticEpochs"]


@pytest.mark.usefixtures("_global_seed_env")
def test_refit_callback_from_the_command_line(tmp_path: Path) -> None:
    """CNNDistanceRefit added to the tiny synthetic config by class_path: Θ refitted after epoch 0 into the run."""
    from test_refit import tiny_seedset

    from synthaug.fit.refit import CNNDistanceRefit

    seeds = tiny_seedset(tmp_path)
    cli = fit_main(tmp_path, "cnn_tiny_synthetic.yaml", "--data.init_args.seed_dir", str(seeds),
                   "--data.init_args.params", "null", "--trainer.max_epochs", "2",
                   "--trainer.limit_train_batches", "2", "--trainer.limit_val_batches", "1",
                   "--trainer.callbacks+=synthaug.fit.refit.CNNDistanceRefit", "--trainer.callbacks.budget", "30")
    (refit,) = [c for c in cli.trainer.callbacks if isinstance(c, CNNDistanceRefit)]
    assert refit.budget == 30 and [h["epoch"] for h in refit.history] == [0]
    assert Path(refit.history[0]["file"]) == Path(cli.trainer.log_dir) / "refit" / "epoch_000.json"
    cfg = _check_run(cli, tmp_path, "synthaug.fit.refit.SyntheticPatchDataModule")
    assert [c["class_path"] for c in cfg["trainer"]["callbacks"]] == ["synthaug.fit.refit.SyntheticEpochs",
                                                                       "synthaug.fit.refit.CNNDistanceRefit"]


@pytest.mark.usefixtures("_global_seed_env")
def test_synthetic_data_without_epoch_callback_gets_one(tmp_path: Path) -> None:
    """A config that picks the synthetic data module by class_path alone still renders new poses every epoch."""
    from test_refit import tiny_seedset

    from synthaug.fit.refit import SyntheticEpochs

    seeds = tiny_seedset(tmp_path)
    cli = fit_main(tmp_path, "cnn_tiny.yaml", "--data", "synthaug.fit.refit.SyntheticPatchDataModule",
                   "--data.init_args.seed_dir", str(seeds), "--data.init_args.synthetic_per_real", "2",
                   "--data.init_args.step_deg", "30", "--data.init_args.sprite_size", "48",
                   "--trainer.max_epochs", "2", "--trainer.limit_train_batches", "1",
                   "--trainer.limit_val_batches", "1")
    assert sum(isinstance(c, SyntheticEpochs) for c in cli.trainer.callbacks) == 1
    assert cli.datamodule.synthetic.epoch == 1


@pytest.mark.usefixtures("_global_seed_env")
def test_drone_configs_instantiate(tmp_path: Path) -> None:
    """The real-data configs name existing classes and arguments (instantiated, not run: no data needed)."""
    spec = importlib.util.spec_from_file_location("synthaug_train_fit", REPO / "train" / "fit.py")
    fit = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fit)
    from synthaug.detectors.lightning_module import PatchDataModule, PatchDetectorModule
    from synthaug.fit.refit import CNNDistanceRefit, SyntheticEpochs, SyntheticPatchDataModule

    expect = {"cnn_drone.yaml": (PatchDataModule, []),
              "cnn_drone_synthetic.yaml": (SyntheticPatchDataModule, [SyntheticEpochs]),
              "cnn_drone_refit.yaml": (SyntheticPatchDataModule, [SyntheticEpochs, CNNDistanceRefit])}
    for name, (data_class, callbacks) in expect.items():
        cli = fit.PatchCLI(PatchDetectorModule, PatchDataModule, subclass_mode_data=True, run=False,
                           args=["--config", str(REPO / "configs" / name), "--trainer.default_root_dir", str(tmp_path),
                                 "--trainer.logger.init_args.save_dir", str(tmp_path)])
        assert type(cli.datamodule) is data_class, name
        assert cli.datamodule.seed_dir == "data/halmstad/seedsets/drone_100"
        ours = [type(c) for c in cli.trainer.callbacks if type(c).__module__.startswith("synthaug")]
        assert ours == callbacks, name
    refit = next(c for c in cli.trainer.callbacks if isinstance(c, CNNDistanceRefit))
    assert (refit.every_n_epochs, refit.budget) == (2, 300)
    assert cli.datamodule.params == "fits/drone_100_hog.json" and cli.datamodule.synthetic_per_real == 20


@pytest.mark.slow
def test_fit_tiny_config(tmp_path: Path) -> None:
    run = run_fit(tmp_path)
    # the resolved configuration is saved with the run
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["data"]["class_path"] == "synthaug.detectors.lightning_module.PatchDataModule"
    assert cfg["model"]["channels"] == [8, 16, 32, 64] and cfg["data"]["init_args"]["generated_positives"] == 150
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
