"""Train a patch detector CNN with Lightning: ``python train/fit.py --config configs/<name>.yaml``.

LightningCLI underneath. ``model:`` is always
:class:`synthaug.detectors.lightning_module.PatchDetectorModule` (its typed
``__init__`` is the schema); ``data:`` picks the data module by ``class_path``
(subclass mode), so one entry point trains on

- real patches only: ``synthaug.detectors.lightning_module.PatchDataModule``
  (a seed set, generated toy patches, or both) — ``configs/cnn_drone.yaml``;
- real + synthetic patches: ``synthaug.fit.refit.SyntheticPatchDataModule``
  (the seeds plus a stream rendered from a ``synthaug fit`` file, new poses
  every epoch through the ``SyntheticEpochs`` callback; the CNN family's
  synthetic defaults of ``synthaug train``: the fit's blurs left out, each
  object on another seed's background) — ``configs/cnn_drone_synthetic.yaml``;
- real + synthetic with Θ refitted against the network while it trains: the
  same data module plus ``synthaug.fit.refit.CNNDistanceRefit`` under
  ``trainer.callbacks`` — ``configs/cnn_drone_refit.yaml``.

``trainer:`` is Lightning's Trainer. The subcommand defaults to ``fit``::

    python train/fit.py --config configs/cnn_tiny.yaml
    python train/fit.py fit --config configs/cnn_tiny.yaml --trainer.max_epochs 5 --data.init_args.batch_size 32

(``--data.batch_size 32`` works too: jsonargparse accepts init arguments
without ``init_args``.) Each run writes, under its log folder
(``<default_root_dir>/<logger>/version_N/``): ``config.yaml`` (the resolved
configuration, with the data module's ``class_path``; LightningCLI's
SaveConfigCallback), ``checkpoints/*.ckpt`` (Lightning, loads with
``weights_only=True``) and ``detector.pt`` (the ``save_detector`` file that
``synthaug detect`` and the ``cnn`` distance read). DDP on CPU:
``--trainer.strategy ddp --trainer.devices 2`` (gloo backend).
"""

from __future__ import annotations

import sys
from pathlib import Path

from lightning.pytorch.cli import LightningCLI

from synthaug.detectors.base import save_detector
from synthaug.detectors.lightning_module import PatchDataModule, PatchDetectorModule

SUBCOMMANDS = ("fit", "validate", "test", "predict")


class PatchCLI(LightningCLI):
    """LightningCLI that also exports ``detector.pt`` after ``fit`` (rank 0 only).

    A synthetic data module (anything with a ``synthetic`` stream, i.e.
    :class:`~synthaug.fit.refit.SyntheticPatchDataModule`) always gets a
    :class:`~synthaug.fit.refit.SyntheticEpochs` callback, added here when the
    configuration does not list one: without it the stream would repeat the
    same poses every epoch.
    """

    def instantiate_classes(self) -> None:
        super().instantiate_classes()
        if self.trainer is None or not hasattr(self.datamodule, "synthetic"):
            return
        from synthaug.fit.refit import SyntheticEpochs

        if not any(isinstance(c, SyntheticEpochs) for c in self.trainer.callbacks):
            self.trainer.callbacks.append(SyntheticEpochs())

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


def _close_process_group() -> None:
    """Destroy the DDP process group, if this process made one.

    Lightning leaves it open after ``fit``; a gloo group still open when the
    interpreter exits can abort the process ("terminate called without an
    active exception", exit -6) after the work is done: gloo's worker threads
    still hold tensors when the interpreter is torn down (pytorch/pytorch
    #190489; PyTorch's shutdown documentation asks each rank to call
    ``destroy_process_group`` at the end of its main).
    """
    import torch.distributed as dist

    if dist.is_available() and dist.is_initialized():
        dist.destroy_process_group()


def main(argv: list[str] | None = None) -> PatchCLI:
    """Run the CLI on ``argv`` (default: the command line), ``fit`` when no subcommand is given."""
    kwargs = {"save_config_kwargs": {"overwrite": True}, "subclass_mode_data": True}
    if argv is None:
        # rewrite sys.argv itself: Lightning's DDP launcher re-runs it for the other ranks
        sys.argv[1:] = _with_subcommand(sys.argv[1:])
        cli = PatchCLI(PatchDetectorModule, PatchDataModule, **kwargs)
    else:
        cli = PatchCLI(PatchDetectorModule, PatchDataModule, args=_with_subcommand(list(argv)), **kwargs)
    # only after success: destroying the group while another rank still waits in a collective would hang
    _close_process_group()
    return cli


if __name__ == "__main__":
    main()
