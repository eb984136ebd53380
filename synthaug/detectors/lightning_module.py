"""Lightning training of the patch CNN: :class:`PatchDetectorModule` and :class:`PatchDataModule`.

The typed ``__init__`` signatures are the configuration schema of
``python train/fit.py --config configs/<name>.yaml`` (LightningCLI). Data come
from a seed-set folder (``SeedSet.load(dir).patches`` as positives,
``.negatives`` and optionally ``.backgrounds`` as negatives), from generated
toy patches (:mod:`synthaug.detectors.toy`, for tests and tiny runs), from
tensors in memory (:meth:`PatchDataModule.from_tensors`), and/or from any user
``Dataset`` of ``(patch (1, S, S) float, label float)`` items.

:func:`fit_patch_detector` is the one training loop of the patch CNN for code
that holds tensors (the experiments' ``train_detector("cnn")``, the d_CNN
distance through :func:`train_patch_cnn`): the same
module and data module under a quiet CPU ``lightning.Trainer``.

Items are pure functions of ``(seed, index)`` (the horizontal-flip augmentation
is the odd half of the index range), so the worker count never changes the
data; the train/val split is drawn once from ``seed``.

Per-positive weights (``positive_weights`` of :meth:`PatchDataModule.from_tensors` and
:func:`fit_patch_detector`; e.g. ``synthaug train --synthetic-share``): each item then carries
its weight, ``(patch, label, weight)`` — a positive keeps its weight through the flip doubling
and the train/val split, negatives weigh 1 — and the loss is the BCE with ``weight=`` (a weight
of 2 counts as the sample twice, 0 as leaving it out). Without them the items are
``(patch, label)`` and the loss is the unweighted BCE, bit-identical to before.

Example:
    >>> dm = PatchDataModule(generated_positives=8, generated_negatives=8, val_fraction=0.25, batch_size=4)
    >>> dm.setup("fit")
    >>> len(dm.train_set), len(dm.val_set)
    (24, 4)
    >>> x, y = next(iter(dm.train_dataloader()))
    >>> x.shape, y.dtype
    (torch.Size([4, 1, 40, 40]), torch.float32)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Sequence

import lightning as L
import torch
from torch import Tensor, nn
from torch.utils.data import ConcatDataset, DataLoader, Dataset

from synthaug._procs import loader_worker_init
from synthaug.detectors.base import check_weights, save_detector
from synthaug.detectors.cnn import CNNDetector, PatchCNN, load_patch_cnn

__all__ = ["PatchDetectorModule", "PatchDataModule", "PatchDataset", "fit_patch_detector", "export_detector",
           "train_patch_cnn"]


class PatchDetectorModule(L.LightningModule):
    """Binary object/background training of a :class:`~synthaug.detectors.cnn.PatchCNN`.

    Args:
        channels: network width ``(c1, c2, c3, c4)``, see ``PatchCNN``.
        window: patch side (40 in the paper).
        lr: Adam learning rate.
        weight_decay: Adam (L2) weight decay.
        pos_weight: weight of the positive class in the BCE loss; None balances
            the classes from the data module's counts when available, else 1.
        init_seed: seeds the weight initialisation.
        shift: each training positive is moved by a random whole-pixel offset in
            ``[-shift, shift]`` (x and y, reflected border; :func:`shift_patches`), a new
            draw every step from ``(init_seed, global_step)``. The network scores
            windows every 8 pixels, so the object rarely sits where the seed crops put
            it; 0 = off.
    """

    def __init__(
        self,
        channels: tuple[int, int, int, int] = (8, 16, 32, 64),
        window: int = 40,
        lr: float = 3e-3,
        weight_decay: float = 1e-4,
        pos_weight: float | None = None,
        init_seed: int = 0,
        shift: int = 0,
    ) -> None:
        super().__init__()
        if shift < 0:
            raise ValueError(f"shift must be >= 0, got {shift}")
        if lr <= 0:
            raise ValueError(f"lr must be > 0, got {lr}")
        if weight_decay < 0:
            raise ValueError(f"weight_decay must be >= 0, got {weight_decay}")
        if pos_weight is not None and pos_weight <= 0:
            raise ValueError(f"pos_weight must be > 0 or None, got {pos_weight}")
        # plain lists/ints/floats only, so the Lightning checkpoint loads with weights_only=True
        self.save_hyperparameters({"channels": [int(c) for c in channels], "window": int(window), "lr": float(lr),
                                   "weight_decay": float(weight_decay), "pos_weight": pos_weight,
                                   "init_seed": int(init_seed), "shift": int(shift)})
        self.net = PatchCNN(channels, window=window, generator=torch.Generator().manual_seed(init_seed))
        self.lr = lr
        self.weight_decay = weight_decay
        self.pos_weight = pos_weight
        self.shift = int(shift)

    def forward(self, x: Tensor) -> Tensor:
        return self.net(x)

    def _pos_weight(self) -> Tensor | None:
        if self.pos_weight is not None:
            return torch.tensor(float(self.pos_weight), device=self.device)
        dm = getattr(self.trainer, "datamodule", None) if self._trainer is not None else None
        ratio = getattr(dm, "negative_positive_ratio", None)
        return None if ratio is None else torch.tensor(float(ratio), device=self.device)

    def _step(self, batch: tuple[Tensor, ...], stage: str) -> Tensor:
        """BCE with the class balance ``pos_weight``; a batch ``(x, y, w)`` weighs each sample's term by ``w``
        (mean over the batch: a weight of 2 counts as the sample twice, 0 as leaving it out)."""
        x, y, *w = batch
        logits = self.net(x)
        # per-sample weights when positive_weights were given; weight=None is the unweighted default, unchanged
        loss = nn.functional.binary_cross_entropy_with_logits(logits, y, weight=w[0].to(logits.dtype) if w else None,
                                                              pos_weight=self._pos_weight())
        acc = ((logits > 0).float() == y).float().mean()
        self.log(f"{stage}_loss", loss, prog_bar=True, sync_dist=stage != "train", batch_size=len(y))
        self.log(f"{stage}_acc", acc, prog_bar=stage != "train", sync_dist=stage != "train", batch_size=len(y))
        return loss

    def training_step(self, batch: tuple[Tensor, ...], batch_idx: int) -> Tensor:
        if self.shift:
            x, y, *w = batch
            g = torch.Generator().manual_seed(int(self.hparams["init_seed"]) * 1_000_003 + int(self.global_step))
            batch = (shift_patches(x, y > 0.5, self.shift, generator=g), y, *w)
        return self._step(batch, "train")

    def validation_step(self, batch: tuple[Tensor, ...], batch_idx: int) -> Tensor:
        return self._step(batch, "val")

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return torch.optim.Adam(self.net.parameters(), lr=self.lr, weight_decay=self.weight_decay)

    def to_detector(self) -> CNNDetector:
        """A copy of the network as a ``save_detector``-able :class:`CNNDetector` (kind "cnn")."""
        net = PatchCNN(self.net.channels, window=self.net.window, generator=torch.Generator())  # weights replaced
        net.load_state_dict({k: v.detach().cpu() for k, v in self.net.state_dict().items()})
        return CNNDetector(net)


def shift_patches(x: Tensor, which: Tensor, shift: int, *, generator: torch.Generator) -> Tensor:
    """Move the patches flagged in ``which`` by random whole-pixel offsets in ``[-shift, shift]``.

    The patch is reflect-padded by ``shift`` and cropped at the offset (no resampling:
    no blur that would tell a shifted positive from a negative). Draws come from
    ``generator`` only; the input is not modified.

    Shape:
        - x: (B, C, S, S), which: (B,) bool
        - output: (B, C, S, S)

    Example:
        >>> x = torch.arange(16.).reshape(1, 1, 4, 4)
        >>> out = shift_patches(x, torch.tensor([True]), 1, generator=torch.Generator().manual_seed(0))
        >>> out.shape, bool((out[0, 0, 1:3, 1:3] != 0).all())
        (torch.Size([1, 1, 4, 4]), True)
    """
    if shift <= 0 or not bool(which.any()):
        return x
    s = x.shape[-1]
    offsets = torch.randint(0, 2 * shift + 1, (int(which.sum()), 2), generator=generator)
    padded = torch.nn.functional.pad(x[which], (shift, shift, shift, shift), mode="reflect")
    moved = torch.stack([p[:, dy:dy + s, dx:dx + s] for p, (dy, dx) in zip(padded, offsets.tolist())])
    out = x.clone()
    out[which] = moved
    return out


class PatchDataset(Dataset):
    """Labelled patches with a deterministic horizontal-flip doubling.

    Item ``i`` is patch ``i // 2``, mirrored when ``i`` is odd (when ``flip``): ``(patch, label)``,
    or ``(patch, label, weight)`` when ``weights`` are given (the mirror image keeps its patch's weight).

    Args:
        patches: float patches in [0, 1], ``(N, 1, S, S)``.
        labels: 1 object, 0 background, ``(N,)``.
        flip: double the set with mirrored copies.
        weights: per-patch loss weights ``(N,)``, >= 0; None: unweighted items.
    """

    def __init__(self, patches: Tensor, labels: Tensor, flip: bool = True, weights: Tensor | None = None) -> None:
        if patches.dim() != 4 or patches.shape[1] != 1 or labels.shape != (patches.shape[0],):
            raise ValueError(f"patches must be (N, 1, S, S) with labels (N,), got {tuple(patches.shape)} and {tuple(labels.shape)}")
        if weights is not None:
            weights = check_weights(weights, labels.shape[0], "weights", "patch", not_all_zero=False).float()
        self.patches = patches.float()
        self.labels = labels.float()
        self.flip = flip
        self.weights = weights

    def __len__(self) -> int:
        return len(self.patches) * (2 if self.flip else 1)

    def __getitem__(self, i: int) -> tuple[Tensor, ...]:
        j, mirrored = (i // 2, i % 2 == 1) if self.flip else (i, False)
        x = self.patches[j]
        if self.weights is None:
            return (x.flip(-1) if mirrored else x), self.labels[j]
        return (x.flip(-1) if mirrored else x), self.labels[j], self.weights[j]


class _UnitWeight(Dataset):
    """A user's ``(patch, label)`` dataset with weight 1 per item (beside weighted patches; a
    ``(patch, label, weight)`` item keeps its weight)."""

    def __init__(self, dataset: Dataset) -> None:
        self.dataset = dataset

    def __len__(self) -> int:
        return len(self.dataset)  # type: ignore[arg-type]

    def __getitem__(self, i: int) -> tuple[Tensor, Tensor, Tensor]:
        x, y, *w = self.dataset[i]  # an item that already carries a weight keeps it
        return x, y, torch.as_tensor(w[0] if w else 1.0, dtype=torch.float32)


def _u8_to_float(a: Any) -> Tensor:
    t = torch.as_tensor(a)
    if t.dtype == torch.uint8:
        t = t.float() / 255.0
    t = t.float()
    return t[:, None] if t.dim() == 3 else t


class PatchDataModule(L.LightningDataModule):
    """Positives and negatives for :class:`PatchDetectorModule`.

    Args:
        seed_dir: a seed-set folder (``synthaug ingest`` output); paths are
            relative to the working directory (the repo root for the configs).
        backgrounds_as_negatives: also use the seed set's object-free background
            crops as negatives.
        generated_positives: number of generated toy object patches to add.
        generated_negatives: number of generated toy background patches to add.
        extra_dataset: any Dataset of ``(patch (1, S, S), label)`` items, added to training.
        val_fraction: fraction of the (seed / generated) patches held out for validation.
        batch_size: mini-batch size.
        num_workers: DataLoader workers.
        flip: mirrored copies as augmentation.
        seed: seeds the split, the shuffling and the generated patches.
    """

    _tensors: tuple[Tensor, Tensor] | None = None  # set by from_tensors before __init__ runs
    _positive_weights: Tensor | None = None  # from_tensors(positive_weights=): one per tensor positive

    def __init__(
        self,
        seed_dir: str | None = None,
        backgrounds_as_negatives: bool = True,
        generated_positives: int = 0,
        generated_negatives: int = 0,
        extra_dataset: Dataset | None = None,
        val_fraction: float = 0.2,
        batch_size: int = 64,
        num_workers: int = 0,
        flip: bool = True,
        seed: int = 0,
    ) -> None:
        super().__init__()
        if not 0.0 <= val_fraction < 1.0:
            raise ValueError(f"val_fraction must be in [0, 1), got {val_fraction}")
        if batch_size < 1:
            raise ValueError(f"batch_size must be >= 1, got {batch_size}")
        if generated_positives < 0 or generated_negatives < 0:
            raise ValueError(f"generated counts must be >= 0, got {generated_positives}, {generated_negatives}")
        if seed_dir is None and generated_positives == 0 and extra_dataset is None and self._tensors is None:
            raise ValueError("PatchDataModule has no data: give seed_dir, generated_positives/negatives or extra_dataset")
        self.seed_dir = seed_dir
        self.backgrounds_as_negatives = backgrounds_as_negatives
        self.generated_positives = generated_positives
        self.generated_negatives = generated_negatives
        self.extra_dataset = extra_dataset
        self.val_fraction = val_fraction
        self.batch_size = batch_size
        self.num_workers = num_workers
        self.flip = flip
        self.seed = seed
        self.negative_positive_ratio: float | None = None
        self.train_set: Dataset | None = None
        self.val_set: Dataset | None = None

    @classmethod
    def from_tensors(cls, positives: Tensor, negatives: Tensor, *, positive_weights: Tensor | None = None,
                     **kwargs: Any) -> "PatchDataModule":
        """A data module over patches in memory (plus whatever ``kwargs`` add).

        The tensors go through the same split, flip doubling and class balance
        as seed-set patches. Not a configuration entry (tensors are no YAML).

        Args:
            positives: object patches ``(P, 1, S, S)``, float in [0, 1] (or uint8).
            negatives: background patches ``(N, 1, S, S)``.
            positive_weights: ``(P,)`` each positive's weight in the loss (>= 0; e.g.
                :func:`~synthaug.detectors.video_training.share_weights`, mean 1 so the class
                balance N/P still holds); every item then carries its weight through the flip
                doubling and the split, negatives (and any other positives) weigh 1. None:
                unweighted ``(patch, label)`` items, as before.
            **kwargs: :class:`PatchDataModule` arguments (``val_fraction``,
                ``batch_size``, ``seed``...).

        Example:
            >>> dm = PatchDataModule.from_tensors(torch.rand(3, 1, 40, 40), torch.rand(5, 1, 40, 40), val_fraction=0.0)
            >>> dm.setup("fit"); len(dm.train_set), dm.negative_positive_ratio
            (16, 1.6666666666666667)
        """
        pos, neg = _u8_to_float(positives), _u8_to_float(negatives)
        if pos.dim() != 4 or neg.dim() != 4 or pos.shape[1] != 1 or pos.shape[1:] != neg.shape[1:]:
            raise ValueError(f"positives and negatives must be (N, 1, S, S) patches of one size, got "
                             f"{tuple(pos.shape)} and {tuple(neg.shape)}")
        if len(pos) == 0 and len(neg) == 0:
            raise ValueError("from_tensors needs at least one patch")
        dm = cls.__new__(cls)
        dm._tensors = (pos, neg)  # before __init__: its no-data check counts them
        if positive_weights is not None:
            dm._positive_weights = check_weights(positive_weights, len(pos), flatten=True)
        dm.__init__(**kwargs)
        return dm

    def load_patches(self) -> tuple[Tensor, Tensor]:
        """All positives and negatives (tensors + seed set + generated), float ``(N, 1, S, S)``."""
        pos: list[Tensor] = []
        neg: list[Tensor] = []
        if self._tensors is not None:
            for parts, x in zip((pos, neg), self._tensors):
                if len(x):
                    parts.append(x)
        if self.seed_dir is not None:
            from synthaug.data.seedset import SeedSet

            s = SeedSet.load(self.seed_dir)
            pos.append(_u8_to_float(s.patches))
            if len(s.negatives):
                neg.append(_u8_to_float(s.negatives))
            if self.backgrounds_as_negatives and len(s.backgrounds):
                neg.append(_u8_to_float(s.backgrounds))
        if self.generated_positives or self.generated_negatives:
            from synthaug.detectors.toy import toy_patches

            gp, gn = toy_patches(self.generated_positives, self.generated_negatives, seed=self.seed)
            pos.append(gp)
            neg.append(gn)
        size = (pos or neg)[0].shape[-1] if (pos or neg) else 40
        empty = torch.zeros(0, 1, size, size)
        return (torch.cat(pos) if pos else empty), (torch.cat(neg) if neg else empty)

    def setup(self, stage: str | None = None) -> None:
        if self.train_set is not None:
            return
        pos, neg = self.load_patches()
        weighted = self._positive_weights is not None
        g = torch.Generator().manual_seed(self.seed)
        train_parts: list[Dataset] = []
        val_parts: list[Dataset] = []
        for x, label in ((pos, 1.0), (neg, 0.0)):
            if len(x) == 0:
                continue
            perm = torch.randperm(len(x), generator=g)
            n_val = int(round(len(x) * self.val_fraction))
            y = torch.full((len(x),), label)
            w = None
            if weighted:  # the tensor positives come first in load_patches; everything else weighs 1
                w = torch.ones(len(x), dtype=torch.float64)
                if label == 1.0:
                    w[: len(self._positive_weights)] = self._positive_weights
                w = w.float()
            train_parts.append(PatchDataset(x[perm[n_val:]], y[perm[n_val:]], self.flip,
                                            weights=None if w is None else w[perm[n_val:]]))
            if n_val:
                val_parts.append(PatchDataset(x[perm[:n_val]], y[perm[:n_val]], flip=False,
                                              weights=None if w is None else w[perm[:n_val]]))
        if self.extra_dataset is not None:
            train_parts.append(_UnitWeight(self.extra_dataset) if weighted else self.extra_dataset)
        if not train_parts:
            raise ValueError(f"no training patches found (seed_dir={self.seed_dir!r})")
        if len(pos) and len(neg):
            self.negative_positive_ratio = len(neg) / len(pos)
        self.train_set = ConcatDataset(train_parts)
        self.val_set = ConcatDataset(val_parts) if val_parts else None

    def train_dataloader(self) -> DataLoader:
        # the shuffle order is drawn from an explicit generator (Lightning's DDP sampler re-seeds it per epoch);
        # fixed patches: the workers may live across epochs
        return DataLoader(self.train_set, batch_size=self.batch_size, shuffle=True, num_workers=self.num_workers,
                          generator=torch.Generator().manual_seed(self.seed), persistent_workers=self.num_workers > 0,
                          worker_init_fn=loader_worker_init())

    def val_dataloader(self) -> DataLoader | list:
        if self.val_set is None:
            return []
        return DataLoader(self.val_set, batch_size=self.batch_size, shuffle=False, num_workers=self.num_workers,
                          worker_init_fn=loader_worker_init())


def fit_patch_detector(
    positives: Tensor,
    negatives: Tensor,
    *,
    channels: Sequence[int] = (8, 16, 32, 64),
    epochs: int = 15,
    batch_size: int = 64,
    lr: float = 3e-3,
    weight_decay: float = 1e-4,
    seed: int = 0,
    val_fraction: float = 0.0,
    shift: int = 0,
    positive_weights: Tensor | None = None,
    module: PatchDetectorModule | None = None,
) -> PatchDetectorModule:
    """Train a :class:`PatchDetectorModule` on patches in memory: the CNN's one training loop.

    ``lightning.Trainer`` on CPU, one device, no logger, no checkpoints, no
    progress bar; the data is :meth:`PatchDataModule.from_tensors` (the
    horizontal-flip doubling is the augmentation; the classes are balanced
    by the loss weight N/P). Deterministic given ``seed``: it seeds the
    weight initialisation and the shuffling (no global RNG is used or changed).

    ``epochs`` counts passes over the patches, as a loop with random flips
    would: training stops after ``ceil(epochs * n / batch_size)`` steps, i.e.
    ``epochs / 2`` epochs of the flip-doubled set (each patch is seen
    ``epochs`` times, in one orientation or the other).

    Args:
        positives: object patches ``(P, 1, S, S)`` in [0, 1].
        negatives: background patches ``(N, 1, S, S)``.
        channels: network width, see :class:`~synthaug.detectors.cnn.PatchCNN`.
        epochs: passes over the training patches (see above).
        batch_size: mini-batch size.
        lr: Adam learning rate.
        weight_decay: Adam weight decay.
        seed: seeds initialisation, split and shuffling.
        val_fraction: patches held out for a validation loss/accuracy each
            epoch (logged only; 0: none).
        shift: random whole-pixel shifts of the positives (:class:`PatchDetectorModule`).
        positive_weights: ``(P,)`` each positive's weight in the BCE loss (``weight=``; negatives 1),
            kept through the flip doubling and the split (:meth:`PatchDataModule.from_tensors`);
            :func:`~synthaug.detectors.video_training.share_weights` gives mean-1 weights, so the
            positive class keeps its total weight (N/P balance) and only its split between real
            and added positives changes. None: the unweighted loss (the default, unchanged).
        module: continue training this module (its weights, a fresh Adam at ``lr``; ``channels`` and the
            initialisation are its own) instead of a new one: fine-tuning. None: a new module.

    Returns:
        The trained module (``.net`` in eval mode; ``.to_detector()`` for a detector).
    """
    import logging
    import warnings

    if positives.dim() != 4 or negatives.dim() != 4 or len(positives) == 0 or len(negatives) == 0:
        raise ValueError(f"positives and negatives must be non-empty (N, 1, S, S), got "
                         f"{tuple(positives.shape)} and {tuple(negatives.shape)}")
    if epochs < 1:
        raise ValueError(f"epochs must be >= 1, got {epochs}")
    dm = PatchDataModule.from_tensors(positives, negatives, val_fraction=val_fraction, batch_size=batch_size,
                                      seed=seed, positive_weights=positive_weights)
    dm.setup("fit")
    n_train = len(dm.train_set) // 2  # the set holds every patch and its mirror image
    max_steps = math.ceil(epochs * n_train / batch_size)
    if module is None:
        module = PatchDetectorModule(tuple(int(c) for c in channels), window=int(positives.shape[-1]), lr=lr,
                                     weight_decay=weight_decay, init_seed=seed, shift=shift)
    else:
        if int(module.net.window) != int(positives.shape[-1]):
            raise ValueError(f"module's window is {module.net.window}, the patches are {positives.shape[-1]} px")
        if lr <= 0:
            raise ValueError(f"lr must be > 0, got {lr}")
        module.lr = lr  # configure_optimizers reads it: a fresh optimiser at the fine-tuning rate
        module.net.train()
    rank_zero = logging.getLogger("lightning.pytorch.utilities.rank_zero")
    level = rank_zero.level
    rank_zero.setLevel(logging.WARNING)  # no "GPU available: ..." banner per call
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*does not have many workers.*")
            warnings.filterwarnings("ignore", message=".*GPU available but not used.*")
            warnings.filterwarnings("ignore", message=".*LeafSpec.*")  # lightning vs torch 2.14 pytree, harmless
            trainer = L.Trainer(accelerator="cpu", devices=1, max_epochs=math.ceil(epochs / 2), max_steps=max_steps,
                                logger=False, enable_checkpointing=False, enable_progress_bar=False,
                                enable_model_summary=False, num_sanity_val_steps=0, log_every_n_steps=1_000_000,
                                limit_val_batches=None if val_fraction > 0 else 0)
            trainer.fit(module, datamodule=dm)
    finally:
        rank_zero.setLevel(level)
    module.net.eval()
    return module


def export_detector(checkpoint: str | Path, out: str | Path) -> Path:
    """Convert a ``PatchDetectorModule`` Lightning checkpoint into a ``save_detector`` file.

    Both files load with ``weights_only=True``; the result is what
    ``synthaug detect`` and the ``cnn`` distance read.

    Raises:
        FileNotFoundError / ValueError: see :func:`~synthaug.detectors.cnn.load_patch_cnn`.
    """
    return save_detector(CNNDetector(load_patch_cnn(checkpoint)), out)


def train_patch_cnn(
    positives: Tensor,
    negatives: Tensor,
    *,
    channels: Sequence[int] = (8, 16, 32, 64),
    epochs: int = 15,
    batch_size: int = 64,
    lr: float = 3e-3,
    weight_decay: float = 1e-4,
    seed: int = 0,
) -> PatchCNN:
    """Train a :class:`PatchCNN` on patches in memory; returns the bare network.

    A thin wrapper over :func:`fit_patch_detector`
    (the :class:`PatchDetectorModule` under a
    quiet CPU ``lightning.Trainer``), so the code base has one training loop:
    for the d_CNN distance ("a CNN trained on the real seed images only") and
    the benchmarks. Classes are balanced by the loss weight; mirrored copies
    of every patch are the augmentation.

    Args:
        positives: object patches ``(P, 1, S, S)`` in [0, 1].
        negatives: background patches ``(N, 1, S, S)``.
        channels: network width, see :class:`PatchCNN`.
        epochs: passes over the data (each patch mirrored or not).
        batch_size: mini-batch size.
        lr: Adam learning rate.
        weight_decay: Adam weight decay.
        seed: seeds initialisation and shuffling.

    Returns:
        The trained network, in eval mode.
    """
    module = fit_patch_detector(positives, negatives, channels=channels, epochs=epochs, batch_size=batch_size, lr=lr,
                                weight_decay=weight_decay, seed=seed)
    return module.to_detector().net
