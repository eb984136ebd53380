"""Synthetic patches in Lightning training, and the d_CNN refit that follows the network.

- :class:`SyntheticPatchDataModule`: :class:`~synthaug.detectors.lightning_module.PatchDataModule`
  (real seeds as positives, backgrounds/negatives as negatives) plus a lazily
  rendered :class:`~synthaug.data.synthetic.SyntheticObjectDataset` stream at
  ``synthetic_per_real`` synthetic patches per real seed, generated from a
  capture-parameter file (``synthaug fit`` output) or sampled.
- :class:`CNNDistanceRefit`: a callback that, every ``every_n_epochs`` epochs,
  freezes a copy of the network being trained, makes it the ``cnn`` distance
  (eq. 6: activations of layers 2..N), refits Θ for every seed against it, and
  hands the new capture parameters to the synthetic stream — so the synthetic
  images follow the network as it learns (issue 5, item 4). Each refit is
  written to ``<log_dir>/refit/epoch_NNN.json``.

- :class:`SyntheticEpochs`: the callback that gives the synthetic stream new
  poses and noise every epoch (``set_epoch``).

From YAML (``python train/fit.py --config ...``, LightningCLI in subclass mode
for ``data:``)::

    data:
      class_path: synthaug.fit.refit.SyntheticPatchDataModule
      init_args: {seed_dir: ..., params: fit.json, synthetic_per_real: 20}
    trainer:
      callbacks:
        - class_path: synthaug.fit.refit.SyntheticEpochs
        - class_path: synthaug.fit.refit.CNNDistanceRefit   # only for the refit
          init_args: {every_n_epochs: 2, budget: 300}

(``train/fit.py`` adds ``SyntheticEpochs`` itself when a synthetic data module
is configured without it.) From Python: ``train/refit_experiment.py``.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import lightning as L
import torch
from torch.utils.data import ConcatDataset, DataLoader, Dataset

from synthaug._procs import loader_worker_init
from synthaug.detectors.lightning_module import PatchDataModule


def refit_with_network(net: Any, seed_dir: str | Path, mesh: Any, out: str | Path, cfg: Any = None, *,
                       first_layer: int = 2, workers: int = 1) -> Path:
    """Θ of every seed refitted with a copy of ``net`` as the ``cnn`` distance (eq. 6: activations of layers
    ``first_layer``..N), written to ``out``: the d_CNN refit, one home for :class:`CNNDistanceRefit` and the mining
    rounds' refit (``synthaug.evaluate.runner``).

    Args:
        net: the network being trained (a :class:`~synthaug.detectors.cnn.PatchCNN`; copied, frozen, on the CPU).
        seed_dir: seed-set folder the network's window matches.
        mesh: mesh path or built-in name.
        out: capture-parameter file to write.
        cfg: fit options (a :class:`~synthaug.fit.config.FitConfig`; its ``distance`` is set to ``"cnn"``);
            None: ``synthaug fit``'s defaults.
        first_layer: first layer of the distance (the paper: 2).
        workers: fit processes.

    Returns:
        ``out``.
    """
    import dataclasses

    from synthaug.distances.cnn import CNNDistance
    from synthaug.fit.config import FitConfig
    from synthaug.fit.run import fit_seedset

    distance = CNNDistance(copy.deepcopy(net).cpu(), first_layer=first_layer)
    cfg = dataclasses.replace(cfg if cfg is not None else FitConfig(), distance="cnn", distance_kwargs={})
    return fit_seedset(seed_dir, mesh, out, cfg, distance=distance, workers=workers)


class SyntheticPatches(Dataset):
    """Adapter: ``SyntheticObjectDataset`` items -> ``(patch, float label)`` for the patch trainer."""

    def __init__(self, dataset: Any) -> None:
        self.dataset = dataset

    def __len__(self) -> int:
        return len(self.dataset)

    def __getitem__(self, i: int) -> tuple[torch.Tensor, torch.Tensor]:
        return self.__getitems__([i])[0]

    def __getitems__(self, indices: list[int]) -> list[tuple[torch.Tensor, torch.Tensor]]:
        return [(img, target["labels"].float()) for img, target in self.dataset.__getitems__(indices)]


class SyntheticPatchDataModule(PatchDataModule):
    """Real seed patches + a synthetic stream generated from the same seeds.

    Args:
        seed_dir: seed-set folder (positives; negatives and backgrounds as negatives).
        mesh: mesh file or built-in name.
        params: capture-parameter file (``synthaug fit``); None samples Θ per seed.
        synthetic_per_real: synthetic positives per real seed.
        synthetic_negative_fraction: fraction of the synthetic items that are
            background-only patches (label 0).
        step_deg, sprite_size: view-cache options.
        effects_off: fitted effects the synthetic stream leaves out; None (the default): the CNN family's
            (:data:`~synthaug.detectors.video_training.FAMILY_EFFECTS_OFF`, those among ``params``' effects), as
            ``synthaug train`` gives the CNN; ``[]`` keeps every effect (the paper).
        background_sampling: ``"seed"`` (the paper: each object on its own seed's background) or ``"other"``;
            None (the default): the CNN family's
            (:data:`~synthaug.detectors.video_training.FAMILY_BACKGROUND_SAMPLING`; a one-seed set keeps its own).
        **kwargs: :class:`PatchDataModule` arguments (batch_size, val_fraction...).
    """

    def __init__(
        self,
        seed_dir: str,
        mesh: str = "quadcopter",
        params: str | None = None,
        synthetic_per_real: float = 10.0,
        synthetic_negative_fraction: float = 0.0,
        step_deg: float = 5.0,
        sprite_size: int = 96,
        backgrounds_as_negatives: bool = True,
        val_fraction: float = 0.2,
        batch_size: int = 64,
        num_workers: int = 0,
        flip: bool = True,
        seed: int = 0,
        effects_off: list[str] | None = None,
        background_sampling: str | None = None,
    ) -> None:
        from synthaug.detectors.video_training import resolve_background_sampling, resolve_effects_off

        super().__init__(seed_dir=seed_dir, backgrounds_as_negatives=backgrounds_as_negatives,
                         val_fraction=val_fraction, batch_size=batch_size, num_workers=num_workers, flip=flip,
                         seed=seed)
        if synthetic_per_real < 0:
            raise ValueError(f"synthetic_per_real must be >= 0, got {synthetic_per_real}")
        self.mesh = mesh
        self.params = params
        self.synthetic_per_real = synthetic_per_real
        self.synthetic_negative_fraction = synthetic_negative_fraction
        self.effects_off = None if effects_off is None else resolve_effects_off("cnn", effects_off)
        self.background_sampling = None if background_sampling is None else \
            resolve_background_sampling("cnn", background_sampling)  # a bad value fails here, not in setup
        self.cache_options = {"step_deg": step_deg, "sprite_size": sprite_size}
        self.synthetic: Any = None

    def setup(self, stage: str | None = None) -> None:
        if self.train_set is not None:
            return
        from synthaug.data.seedset import SeedSet
        from synthaug.data.synthetic import SyntheticObjectDataset
        from synthaug.detectors.video_training import resolve_background_sampling, resolve_effects_off
        from synthaug.params import CaptureParams, resolve_effect_names

        super().setup(stage)
        seeds = SeedSet.load(self.seed_dir)
        n_syn = int(round(self.synthetic_per_real * len(seeds)))
        # the effects Θ carries: the fit's, or those CaptureParams.sample draws when there is no fit
        effects = tuple(CaptureParams.load(self.params).effects if self.params is not None
                        else resolve_effect_names(None))
        try:  # None: the CNN family's, those among Θ's effects
            off = resolve_effects_off("cnn", self.effects_off, available=effects)
        except ValueError as e:
            raise ValueError(f"effects_off of {self.params or 'sampled Θ'}: {e}") from None
        self.synthetic = SyntheticObjectDataset(
            self.mesh, seeds, self.params, length=n_syn, patch_size=seeds.patch_size,
            negative_fraction=self.synthetic_negative_fraction, seed=self.seed, render=self.cache_options,
            effects=[e for e in effects if e not in off] if off else None,
            background_sampling=resolve_background_sampling("cnn", self.background_sampling, len(seeds)))
        self.train_set = ConcatDataset([*self.train_set.datasets, SyntheticPatches(self.synthetic)])

    def train_dataloader(self) -> DataLoader:
        # persistent_workers=False on purpose: the workers hold copies of the dataset, so the epoch that
        # SyntheticEpochs sets (new poses) and the Θ of a CNNDistanceRefit reach them only because Lightning
        # re-creates them for every epoch (iter() runs after on_train_epoch_start from epoch 1 on).
        # Workers must be re-created anyway when CNNDistanceRefit swaps Θ, and the stream sits inside a
        # ConcatDataset (integer indices), so EpochSampler (which carries the epoch in the index) is not used here.
        return DataLoader(self.train_set, batch_size=self.batch_size, shuffle=True, num_workers=self.num_workers,
                          generator=torch.Generator().manual_seed(self.seed + 7919 * self._epoch()),
                          persistent_workers=False, worker_init_fn=loader_worker_init())

    def _epoch(self) -> int:
        trainer = getattr(self, "trainer", None)
        return int(trainer.current_epoch) if trainer is not None else 0

    def update_params(self, params: Any, scales: torch.Tensor | None = None) -> None:
        """Swap in new capture parameters (one row per seed) for the synthetic stream."""
        if self.synthetic is None:
            raise RuntimeError("setup() has not run")
        if params.batch_size != self.synthetic.params.batch_size:
            raise ValueError(f"expected {self.synthetic.params.batch_size} rows, got {params.batch_size}")
        self.synthetic.params = params
        if scales is not None:
            self.synthetic.seed_scales = scales


class SyntheticEpochs(L.Callback):
    """Calls ``set_epoch`` on the synthetic stream: new poses and noise every epoch."""

    def on_train_epoch_start(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        dm = trainer.datamodule
        if getattr(dm, "synthetic", None) is not None:
            dm.synthetic.set_epoch(trainer.current_epoch)


class CNNDistanceRefit(L.Callback):
    """Refit Θ per seed with the current network as d_CNN, every ``every_n_epochs`` epochs.

    Args:
        every_n_epochs: refit period.
        budget: objective evaluations per seed per refit.
        first_layer: first CNN layer of the distance (the paper: 2).
        optimizer: ``cmaes`` or ``anneal``.
        seed: base seed of the fits.
    """

    def __init__(self, every_n_epochs: int = 1, budget: int = 400, first_layer: int = 2, optimizer: str = "cmaes",
                 seed: int = 0) -> None:
        if every_n_epochs < 1:
            raise ValueError(f"every_n_epochs must be >= 1, got {every_n_epochs}")
        self.every_n_epochs = every_n_epochs
        self.budget = budget
        self.first_layer = first_layer
        self.optimizer = optimizer
        self.seed = seed
        self.history: list[dict[str, Any]] = []

    def on_train_epoch_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        epoch = trainer.current_epoch
        if (epoch + 1) % self.every_n_epochs or epoch + 1 >= trainer.max_epochs:
            return
        dm = trainer.datamodule
        if not isinstance(dm, SyntheticPatchDataModule) or dm.synthetic is None:
            raise ValueError("CNNDistanceRefit needs a SyntheticPatchDataModule")
        from synthaug.fit.config import FitConfig
        from synthaug.params import CaptureParams, fitted_object_scales

        out_dir = Path(trainer.log_dir or trainer.default_root_dir) / "refit"
        out = out_dir / f"epoch_{epoch:03d}.json"
        if trainer.is_global_zero:
            cfg = FitConfig(distance="cnn", optimizer=self.optimizer, budget=self.budget, seed=self.seed + epoch,
                            step_deg=dm.cache_options["step_deg"], sprite_size=dm.cache_options["sprite_size"])
            refit_with_network(pl_module.net, dm.seed_dir, dm.mesh, out, cfg, first_layer=self.first_layer)
        trainer.strategy.barrier()
        params, extra, meta = CaptureParams.load_with_extra(out)
        scales = fitted_object_scales(extra)
        dm.update_params(params, scales)
        med = float(meta["distance_median"])
        self.history.append({"epoch": epoch, "file": str(out), "distance_median": med})
        pl_module.log("refit_distance_median", med, sync_dist=False)
