"""Lightning DDP on CPU: 2 processes, gloo backend, the tiny config."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from test_fit_cli import run_fit


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
