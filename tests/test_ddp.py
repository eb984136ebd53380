"""Lightning DDP on CPU: 2 processes, gloo backend, the tiny config."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from test_fit_cli import fit_main, run_fit


@pytest.mark.slow
def test_ddp_two_cpu_processes(tmp_path: Path) -> None:
    if not torch.distributed.is_available() or not torch.distributed.is_gloo_available():
        pytest.skip("torch.distributed with gloo is not available in this build")
    run = run_fit(tmp_path, "--trainer.strategy", "ddp", "--trainer.devices", "2", "--trainer.max_epochs", "1",
                  "--data.generated_positives", "64", "--data.generated_negatives", "64", timeout=180)
    (ckpt,) = run.glob("checkpoints/*.ckpt")
    state = torch.load(ckpt, map_location="cpu", weights_only=True)
    # 2 x (64 + 64) x 0.8 = 204 training items (flip-doubled), batch 64, split over 2 ranks -> 2 steps each
    assert state["global_step"] == 2, state["global_step"]
    from synthaug.detectors.base import load_detector

    det = load_detector(run / "detector.pt")
    assert det.score_patches(torch.rand(2, 1, 40, 40)).shape == (2,)


@pytest.mark.slow
def test_fit_destroys_its_process_group(tmp_path: Path, monkeypatch) -> None:
    # a gloo group left open at interpreter exit can abort the process after a good fit (exit -6)
    if not torch.distributed.is_available() or not torch.distributed.is_gloo_available():
        pytest.skip("torch.distributed with gloo is not available in this build")
    monkeypatch.setenv("PL_GLOBAL_SEED", "0")
    monkeypatch.setenv("MASTER_ADDR", "127.0.0.1")
    monkeypatch.setenv("MASTER_PORT", "29531")
    seen = []
    real_init = torch.distributed.init_process_group

    def spy(*args, **kwargs):
        seen.append(kwargs.get("backend", args[0] if args else None))
        return real_init(*args, **kwargs)

    monkeypatch.setattr(torch.distributed, "init_process_group", spy)
    fit_main(tmp_path, "cnn_tiny.yaml", "--trainer.strategy", "ddp", "--trainer.devices", "1",
             "--trainer.max_epochs", "1", "--data.generated_positives", "16", "--data.generated_negatives", "16")
    assert seen == ["gloo"]  # the fit did make a group ...
    assert not torch.distributed.is_initialized()  # ... and closed it
