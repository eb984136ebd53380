"""Train a patch detector CNN with Lightning: ``python train/fit.py --config configs/<name>.yaml``.

LightningCLI underneath: the typed ``__init__`` of
:class:`synthaug.detectors.lightning_module.PatchDetectorModule` (``model:``) and
:class:`~synthaug.detectors.lightning_module.PatchDataModule` (``data:``) are
the schema, ``trainer:`` is Lightning's Trainer. The subcommand defaults to
``fit``, so both of these work::

    python train/fit.py --config configs/cnn_tiny.yaml
    python train/fit.py fit --config configs/cnn_tiny.yaml --trainer.max_epochs 5

Each run writes, under its log folder (``<default_root_dir>/<logger>/version_N/``):
``config.yaml`` (the resolved configuration, LightningCLI's SaveConfigCallback),
``checkpoints/*.ckpt`` (Lightning, loads with ``weights_only=True``) and
``detector.pt`` (the ``save_detector`` file that ``synthaug detect`` and the
``cnn`` distance read). DDP on CPU: ``--trainer.strategy ddp --trainer.devices 2``
(gloo backend).
"""

from __future__ import annotations

import sys
from pathlib import Path

from lightning.pytorch.cli import LightningCLI

from synthaug.detectors.base import save_detector
from synthaug.detectors.lightning_module import PatchDataModule, PatchDetectorModule

SUBCOMMANDS = ("fit", "validate", "test", "predict")


class PatchCLI(LightningCLI):
    """LightningCLI that also exports ``detector.pt`` after ``fit`` (rank 0 only)."""

    def after_fit(self) -> None:
        trainer = self.trainer
        log_dir = trainer.log_dir  # a collective call under DDP: every rank must make it
        if not trainer.is_global_zero:
            return
        out_dir = Path(log_dir or trainer.default_root_dir)
        path = save_detector(self.model.to_detector(), out_dir / "detector.pt")
        print(f"detector exported to {path}")


def _with_subcommand(argv: list[str]) -> list[str]:
    if any(a in SUBCOMMANDS for a in argv) or argv[:1] in (["-h"], ["--help"]):
        return argv
    return ["fit", *argv]


def main(argv: list[str] | None = None) -> PatchCLI:
    """Run the CLI on ``argv`` (default: the command line), ``fit`` when no subcommand is given."""
    kwargs = {"save_config_kwargs": {"overwrite": True}}
    if argv is None:
        # rewrite sys.argv itself: Lightning's DDP launcher re-runs it for the other ranks
        sys.argv[1:] = _with_subcommand(sys.argv[1:])
        return PatchCLI(PatchDetectorModule, PatchDataModule, **kwargs)
    return PatchCLI(PatchDetectorModule, PatchDataModule, args=_with_subcommand(list(argv)), **kwargs)


if __name__ == "__main__":
    main()
