"""Train a torchvision detector on real + synthetic frames: ``python train/detector_tv.py --config CONFIG``.

LightningCLI underneath (issue 14 part 8). ``model:`` is :class:`TorchvisionDetector`
(a torchvision detection model trained from scratch: ``weights=None,
weights_backbone=None``, nothing is downloaded), ``data:`` is
:class:`SyntheticFramesDataModule` (a seed set's real frames with their labelled
box, mixed with synthetic frames of the object composited into the seed set's
background frames by :class:`~synthaug.data.synthetic.SyntheticObjectDataset`
in ``mode="frame"``; new poses every epoch through
:class:`~synthaug.data.synthetic.EpochSampler`). ``trainer:`` is Lightning's
Trainer. The subcommand defaults to ``fit``::

    python train/detector_tv.py --config configs/detector_tv_tiny.yaml
    python train/detector_tv.py fit --config configs/detector_tv_drone.yaml \\
        --trainer.accelerator gpu --trainer.devices 1 --data.batch_size 32 --trainer.max_epochs 60

Each run writes, under its log folder (``<default_root_dir>/<logger>/version_N/``):
``config.yaml`` (the resolved configuration), ``metrics.csv`` (CSVLogger:
``train_loss`` and its parts, ``val_map_50``, ``val_map``), Lightning
checkpoints when enabled, and at the end of ``fit``

- ``detector_tv.pt``: the torchvision model's ``state_dict`` (tensors only:
  ``torch.load(path, weights_only=True)``), the final weights;
- ``detector_tv.json``: the arguments of :func:`build_model` that rebuild its
  architecture; :func:`load_detector_tv` reads both and returns the model in
  eval mode.

Choices (and why):

- **Gray frames -> 3 channels in the module.** Seed sets and gray fits give
  1-channel frames (the dataset's ``channels`` must equal the fit's), so the
  dataset stays gray (a third of the memory and worker traffic) and
  :func:`to_model_input` repeats a 1-channel frame to 3 channels before the
  torchvision model, in training, validation and for a loaded model. RGB
  frames (an RGB fit) pass unchanged.
- **No big rescaling.** torchvision's ``GeneralizedRCNNTransform`` scales every
  frame by ``min(min_size / short side, max_size / long side)``. The defaults
  of the 320 model (320 / 640) would upscale a 128 x 96 frame 3.3x and shrink
  the 640 x 512 Halmstad frames to 62 % (a 23 px drone to 14 px); set
  ``min_size`` / ``max_size`` to the frames' own short / long side to train at
  native resolution (``configs/detector_tv_drone.yaml``: 512 / 640). The module
  warns once when the first training frame is rescaled by more than 2x either
  way. ``ssdlite320_mobilenet_v3_large`` resizes to a fixed size instead: width
  ``max_size`` x height ``min_size``. ``anchor_sizes`` (Faster R-CNN, five
  sizes) lowers the anchors for small objects (default 32 ... 512 px).
- **Validation by video, real frames only.** ``val_fraction`` of the seeds is
  held out as whole videos (the records' ``video``; seeds without one count
  as their own video): neither their frames nor their background frames are
  seen in training (synthetic frames use the training seeds' backgrounds and
  capture parameters only). Validation reports ``val_map_50``: torchmetrics'
  ``MeanAveragePrecision`` (COCO-style, pycocotools) at IoU 0.5 on those real
  frames.

Tested on one device (CPU; the GPU run is the same code on ``--trainer.accelerator
gpu --trainer.devices 1``). Under DDP, Lightning (2.6) wraps the ``EpochSampler``
in its ``DistributedSamplerWrapper``, which shards the ``(epoch, index)`` pairs and
forwards ``set_epoch``; that path is not tested here.
"""

from __future__ import annotations

import json
import math
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal

import lightning as L
import torch
from lightning.pytorch.cli import LightningCLI
from torch import Tensor, nn
from torch.utils.data import DataLoader, Dataset, Subset
from torchvision import tv_tensors

SUBCOMMANDS = ("fit", "validate", "test", "predict")
WEIGHTS_FILE = "detector_tv.pt"
ARCH_FILE = "detector_tv.json"

Arch = Literal["fasterrcnn_mobilenet_v3_large_320_fpn", "fasterrcnn_mobilenet_v3_large_fpn",
               "ssdlite320_mobilenet_v3_large"]
ARCHS: tuple[str, ...] = Arch.__args__  # type: ignore[attr-defined]


# ------------------------------------------------------------------ model
def build_model(arch: str = "fasterrcnn_mobilenet_v3_large_320_fpn", num_classes: int = 2, min_size: int = 320,
                max_size: int = 640, anchor_sizes: Sequence[int] | None = None) -> nn.Module:
    """A torchvision detection model with random weights (``weights=None, weights_backbone=None``).

    Args:
        arch: ``fasterrcnn_mobilenet_v3_large_320_fpn`` (default; small and fast),
            ``fasterrcnn_mobilenet_v3_large_fpn`` (same network, more RPN proposals
            at test time) or ``ssdlite320_mobilenet_v3_large``.
        num_classes: including the background class (2: background + the object).
        min_size, max_size: Faster R-CNN scales each frame by
            ``min(min_size / short side, max_size / long side)``; SSDlite resizes
            every frame to width ``max_size`` x height ``min_size``.
        anchor_sizes: Faster R-CNN only: five anchor sizes in pixels of the
            rescaled frame (default ``32 64 128 256 512``), the same on every
            feature map (aspect ratios 0.5, 1, 2).

    Example:
        >>> m = build_model(min_size=96, max_size=128, anchor_sizes=[16, 32, 64, 128, 256])
        >>> m.transform.min_size, m.rpn.anchor_generator.sizes[0]
        ((96,), (16, 32, 64, 128, 256))
    """
    from torchvision.models import detection

    if arch not in ARCHS:
        raise ValueError(f"arch must be one of {list(ARCHS)}, got {arch!r}")
    if num_classes < 2:
        raise ValueError(f"num_classes must be >= 2 (background + object), got {num_classes}")
    if not 16 <= min_size <= max_size:
        raise ValueError(f"need 16 <= min_size <= max_size, got {min_size}, {max_size}")
    if arch.startswith("ssdlite"):
        if anchor_sizes is not None:
            raise ValueError("anchor_sizes is for the Faster R-CNN archs (SSDlite's default boxes are relative)")
        from torchvision.models.detection.transform import GeneralizedRCNNTransform

        model = detection.ssdlite320_mobilenet_v3_large(weights=None, weights_backbone=None, num_classes=num_classes)
        t = model.transform
        model.transform = GeneralizedRCNNTransform(min_size, max_size, t.image_mean, t.image_std, size_divisible=1,
                                                   fixed_size=(max_size, min_size))  # (width, height)
        model.detections_per_img = 100  # (300 by default) COCO-style mAP counts the best 100 per image
        return model
    model = getattr(detection, arch)(weights=None, weights_backbone=None, num_classes=num_classes,
                                     min_size=min_size, max_size=max_size)
    if anchor_sizes is not None:
        from torchvision.models.detection.anchor_utils import AnchorGenerator

        old = model.rpn.anchor_generator
        sizes = tuple(int(s) for s in anchor_sizes)
        if len(sizes) != len(old.sizes[0]) or min(sizes) < 1:
            raise ValueError(f"anchor_sizes must be {len(old.sizes[0])} positive sizes (the RPN head predicts "
                             f"{old.num_anchors_per_location()[0]} anchors per location), got {list(anchor_sizes)}")
        model.rpn.anchor_generator = AnchorGenerator((sizes,) * len(old.sizes), old.aspect_ratios)
    return model


def to_model_input(images: Sequence[Tensor]) -> list[Tensor]:
    """Frames as the torchvision model takes them: plain float tensors, gray (1, H, W) frames repeated to 3 channels."""
    out = []
    for img in images:
        t = img.as_subclass(Tensor) if isinstance(img, Tensor) else torch.as_tensor(img)
        if t.ndim == 2:
            t = t[None]
        if t.shape[0] == 1:
            t = t.expand(3, -1, -1)
        if t.shape[0] != 3:
            raise ValueError(f"expected (1|3, H, W) frames, got shape {tuple(t.shape)}")
        out.append(t.float())
    return out


def load_detector_tv(path: str | Path, map_location: Any = "cpu") -> nn.Module:
    """The model saved by a run: ``detector_tv.pt`` (weights) + ``detector_tv.json`` beside it, in eval mode.

    Feed it frames through :func:`to_model_input` (gray frames become 3-channel).
    """
    path = Path(path)
    arch_file = path.with_suffix(".json")
    if not arch_file.is_file():
        raise FileNotFoundError(f"{arch_file} not found (it holds the arguments of build_model for {path.name})")
    model = build_model(**json.loads(arch_file.read_text()))
    model.load_state_dict(torch.load(path, map_location=map_location, weights_only=True))
    return model.eval()


class TorchvisionDetector(L.LightningModule):
    """A torchvision detection model trained with Lightning.

    ``training_step`` sums the model's loss dict (logged as ``train_loss``, the
    parts as ``train_<name>``); ``validation_step`` feeds the predictions to
    ``torchmetrics.detection.MeanAveragePrecision`` (``box_format="xyxy"``),
    logged as ``val_map_50`` (IoU 0.5) and ``val_map`` (mean over
    ``map_iou_thresholds``).

    Args:
        arch, num_classes, min_size, max_size, anchor_sizes: see :func:`build_model`.
        optimizer: ``sgd`` (momentum, Nesterov off) or ``adamw``.
        lr: peak learning rate.
        momentum: SGD momentum (AdamW: beta1).
        weight_decay: weight decay (decoupled for AdamW).
        warmup_steps: linear warm-up from ``lr / 100`` over this many optimizer
            steps (training from scratch with SGD is unstable without one).
        scheduler: ``none`` (constant after warm-up) or ``cosine`` (decay to 0
            over the run's ``estimated_stepping_batches``).
        map_iou_thresholds: IoU thresholds of ``val_map`` (None: COCO's 0.5:0.95);
            0.5 is always included for ``val_map_50``.
    """

    def __init__(
        self,
        arch: Arch = "fasterrcnn_mobilenet_v3_large_320_fpn",
        num_classes: int = 2,
        min_size: int = 320,
        max_size: int = 640,
        anchor_sizes: list[int] | None = None,
        optimizer: Literal["sgd", "adamw"] = "sgd",
        lr: float = 0.01,
        momentum: float = 0.9,
        weight_decay: float = 1e-4,
        warmup_steps: int = 0,
        scheduler: Literal["none", "cosine"] = "none",
        map_iou_thresholds: list[float] | None = None,
    ) -> None:
        super().__init__()
        if optimizer not in ("sgd", "adamw"):
            raise ValueError(f"optimizer must be 'sgd' or 'adamw', got {optimizer!r}")
        if scheduler not in ("none", "cosine"):
            raise ValueError(f"scheduler must be 'none' or 'cosine', got {scheduler!r}")
        if not (lr > 0 and math.isfinite(lr)) or weight_decay < 0 or warmup_steps < 0:
            raise ValueError(f"need lr > 0, weight_decay >= 0, warmup_steps >= 0; got {lr}, {weight_decay}, "
                             f"{warmup_steps}")
        self.save_hyperparameters()
        self.arch_args = {"arch": arch, "num_classes": num_classes, "min_size": min_size, "max_size": max_size,
                          "anchor_sizes": None if anchor_sizes is None else [int(s) for s in anchor_sizes]}
        self.detector = build_model(**self.arch_args)
        from torchmetrics.detection import MeanAveragePrecision

        ious = None if map_iou_thresholds is None else sorted({0.5, *(float(t) for t in map_iou_thresholds)})
        self.val_map = MeanAveragePrecision(box_format="xyxy", iou_type="bbox", iou_thresholds=ious)
        self._scale_checked = False

    def forward(self, images: Sequence[Tensor]) -> list[dict[str, Tensor]]:
        """Predictions (``boxes`` XYXY in input pixels, ``scores``, ``labels``) for frames (1 or 3 channels)."""
        return self.detector(to_model_input(images))

    @staticmethod
    def _targets(targets: Sequence[dict[str, Any]]) -> list[dict[str, Tensor]]:
        return [{"boxes": t["boxes"].as_subclass(Tensor).float().reshape(-1, 4),
                 "labels": t["labels"].as_subclass(Tensor).long().reshape(-1)} for t in targets]

    def _check_scale(self, image: Tensor) -> None:
        if self._scale_checked:
            return
        self._scale_checked = True
        h, w = image.shape[-2:]
        if self.hparams.arch.startswith("ssdlite"):
            s = max(self.hparams.min_size / h, self.hparams.max_size / w, h / self.hparams.min_size,
                    w / self.hparams.max_size)
        else:
            s = min(self.hparams.min_size / min(h, w), self.hparams.max_size / max(h, w))
            s = max(s, 1 / s)
        if s > 2:
            warnings.warn(f"the model rescales {w}x{h} frames by more than 2x (min_size={self.hparams.min_size}, "
                          f"max_size={self.hparams.max_size}); set them near the frames' short / long side",
                          stacklevel=2)

    def training_step(self, batch: tuple[Sequence[Tensor], Sequence[dict[str, Any]]], batch_idx: int) -> Tensor:
        images, targets = batch
        self._check_scale(images[0])
        losses = self.detector(to_model_input(images), self._targets(targets))
        loss = sum(losses.values())
        n = len(images)
        self.log("train_loss", loss, prog_bar=True, batch_size=n)
        for k, v in losses.items():
            self.log(f"train_{k}", v, batch_size=n)
        return loss

    def validation_step(self, batch: tuple[Sequence[Tensor], Sequence[dict[str, Any]]], batch_idx: int) -> None:
        images, targets = batch
        preds = self.detector(to_model_input(images))
        self.val_map.update([{k: p[k] for k in ("boxes", "scores", "labels")} for p in preds], self._targets(targets))

    def on_validation_epoch_end(self) -> None:
        res = self.val_map.compute()
        self.val_map.reset()
        self.log("val_map_50", res["map_50"].float(), prog_bar=True)
        self.log("val_map", res["map"].float())

    def configure_optimizers(self) -> Any:
        hp = self.hparams
        params = [p for p in self.detector.parameters() if p.requires_grad]
        if hp.optimizer == "sgd":
            opt = torch.optim.SGD(params, lr=hp.lr, momentum=hp.momentum, weight_decay=hp.weight_decay)
        else:
            opt = torch.optim.AdamW(params, lr=hp.lr, betas=(hp.momentum, 0.999), weight_decay=hp.weight_decay)
        if hp.warmup_steps == 0 and hp.scheduler == "none":
            return opt
        total = None
        if hp.scheduler == "cosine":
            total = self.trainer.estimated_stepping_batches if self._trainer is not None else None
            if total is None or not math.isfinite(total):
                raise ValueError("scheduler='cosine' needs a finite run length (trainer max_epochs or max_steps)")
            total = max(int(total), 1)
        warm = int(hp.warmup_steps)

        def factor(step: int) -> float:
            f = 1.0
            if warm and step < warm:
                f = 0.01 + 0.99 * step / warm
            if total is not None:
                f *= 0.5 * (1 + math.cos(math.pi * min(step, total) / total))
            return f

        sched = torch.optim.lr_scheduler.LambdaLR(opt, factor)
        return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "interval": "step"}}


# ------------------------------------------------------------------ data
class RealFrames(Dataset):
    """Real ``(frame, {"boxes", ...})`` pairs in the frame-mode item format (tv_tensors, float (1, H, W) in [0, 1],
    boxes clipped to the frame, ``labels`` = ``label``) for validation."""

    def __init__(self, frames: Any, label: int = 1) -> None:
        self.frames = frames
        self.label = int(label)

    def __len__(self) -> int:
        return len(self.frames)

    def __getitem__(self, i: int) -> tuple[tv_tensors.Image, dict[str, Any]]:
        frame, target = self.frames[i]
        img = torch.as_tensor(frame)
        img = (img.float() / 255.0 if img.dtype == torch.uint8 else img.float())
        img = img[None] if img.ndim == 2 else img.permute(2, 0, 1)  # (H, W) or (H, W, C) arrays
        h, w = img.shape[-2:]
        boxes = torch.as_tensor(target["boxes"], dtype=torch.float32).reshape(-1, 4).clone()
        boxes[:, 0::2] = boxes[:, 0::2].clamp(0, w)
        boxes[:, 1::2] = boxes[:, 1::2].clamp(0, h)
        boxes = boxes[(boxes[:, 2] > boxes[:, 0]) & (boxes[:, 3] > boxes[:, 1])]
        return tv_tensors.Image(img), {
            "boxes": tv_tensors.BoundingBoxes(boxes, format="XYXY", canvas_size=(h, w)),
            "labels": torch.full((len(boxes),), self.label, dtype=torch.int64),
        }


def video_split(records: Sequence[dict[str, Any]], val_fraction: float, seed: int = 0) -> tuple[list[int], list[int]]:
    """``(train, val)`` seed indices: whole videos (records' ``video``) held out until ``val_fraction`` of the seeds.

    Videos are taken in a seeded random order; a seed without ``video`` is its
    own group. At least one seed stays in training; ``val_fraction > 0`` with
    two or more groups holds out at least one (``round(val_fraction * n)`` seeds, more when
    a video is larger).

    Example:
        >>> video_split([{"video": "a"}, {"video": "a"}, {"video": "b"}, {}], 0.25, seed=0)
        ([0, 1, 3], [2])
    """
    if not 0.0 <= val_fraction < 1.0:
        raise ValueError(f"val_fraction must be in [0, 1), got {val_fraction}")
    groups: dict[str, list[int]] = {}
    for i, r in enumerate(records):
        groups.setdefault(str(r["video"]) if r.get("video") is not None else f"\0seed{i}", []).append(i)
    names = sorted(groups)
    order = torch.randperm(len(names), generator=torch.Generator().manual_seed(seed)).tolist()
    n = len(records)
    target = max(1, round(val_fraction * n))
    val: list[int] = []
    if val_fraction > 0 and len(names) >= 2:
        for k in order:
            if len(val) >= target:
                break
            group = groups[names[k]]
            if len(val) + len(group) < n:  # keep at least one training seed
                val += group
    val_set = set(val)
    return [i for i in range(len(records)) if i not in val_set], sorted(val)


class SyntheticFramesDataModule(L.LightningDataModule):
    """Real seed frames + synthetic frames (frame mode) for :class:`TorchvisionDetector`.

    Training: the training seeds' real frames with their labelled box
    (:func:`synthaug.data.export.seedset_real_frames`) as ``real=`` of a
    :class:`~synthaug.data.synthetic.SyntheticObjectDataset` in frame mode, with
    ``synthetic_per_real`` synthetic frames per real one (the object rendered
    with the training seeds' capture parameters and background frames), drawn
    through an :class:`~synthaug.data.synthetic.EpochSampler` (new poses every
    epoch, also with persistent workers; Lightning calls its ``set_epoch``).
    Validation: the held-out seeds' real frames (whole videos, see
    :func:`video_split`), no synthetic ones.

    Args:
        seed_dir: seed-set folder (``synthaug ingest``); paths relative to the working directory.
        params: ``synthaug fit`` output with one row per seed of ``seed_dir``
            (None: one row per seed sampled from the default ranges with ``seed``).
        mesh: mesh file or built-in name.
        synthetic_per_real: synthetic frames per real training frame.
        object_size: (min, max) object size in frame pixels (the mesh's longest side).
        negative_fraction: fraction of synthetic frames without the object.
        val_fraction: fraction of the seeds held out (as whole videos) for validation.
        batch_size: frames per batch.
        num_workers: DataLoader workers (persistent when > 0).
        seed: seeds the split, the synthetic items, the shuffling and the augmentation.
        step_deg: view-cache grid step in degrees.
        sprite_size: view-cache sprite side (None: ``max(128, 2 x max object size)``).
        hflip: random horizontal flips (training, real and synthetic frames alike).
        jitter: random brightness and contrast factors in ``[1 - jitter, 1 + jitter]`` (training; 0: off).
    """

    def __init__(
        self,
        seed_dir: str,
        params: str | None = None,
        mesh: str = "quadcopter",
        synthetic_per_real: float = 10.0,
        object_size: tuple[float, float] = (20.0, 60.0),
        negative_fraction: float = 0.0,
        val_fraction: float = 0.2,
        batch_size: int = 8,
        num_workers: int = 0,
        seed: int = 0,
        step_deg: float = 5.0,
        sprite_size: int | None = None,
        hflip: bool = True,
        jitter: float = 0.0,
    ) -> None:
        super().__init__()
        if batch_size < 1:
            raise ValueError(f"batch_size must be >= 1, got {batch_size}")
        if not 0.0 <= val_fraction < 1.0:
            raise ValueError(f"val_fraction must be in [0, 1), got {val_fraction}")
        if not 0.0 <= jitter < 1.0:
            raise ValueError(f"jitter must be in [0, 1), got {jitter}")
        self.save_hyperparameters()
        self.train_set: Any = None
        self.val_set: Dataset | None = None
        self.train_seeds: list[int] = []
        self.val_seeds: list[int] = []

    def train_transforms(self) -> Any:
        from torchvision.transforms import v2

        steps: list[Any] = [v2.ClampBoundingBoxes()]
        if self.hparams.hflip:
            steps.append(v2.RandomHorizontalFlip(0.5))
        if self.hparams.jitter > 0:
            steps.append(v2.ColorJitter(brightness=self.hparams.jitter, contrast=self.hparams.jitter))
        steps.append(v2.SanitizeBoundingBoxes())  # drops boxes left without area (and their labels)
        return v2.Compose(steps)

    def setup(self, stage: str | None = None) -> None:
        if self.train_set is not None:
            return
        from synthaug.data.export import seedset_real_frames
        from synthaug.data.seedset import SeedSet
        from synthaug.data.synthetic import SyntheticObjectDataset
        from synthaug.params import CaptureParams
        from synthaug.render.cache import ViewCache

        hp = self.hparams
        seeds = SeedSet.load(hp.seed_dir)
        if len(seeds) == 0:
            raise ValueError(f"{hp.seed_dir} holds no seeds")
        train, val = video_split(seeds.records, hp.val_fraction, hp.seed)
        self.train_seeds, self.val_seeds = train, val
        params = None
        if hp.params is not None:
            params = CaptureParams.load(hp.params)
            if params.batch_size != len(seeds):
                raise ValueError(f"{hp.params} has {params.batch_size} rows but {hp.seed_dir} has {len(seeds)} seeds "
                                 f"(one row per seed)")
            params = params[torch.tensor(train)]
        lo, hi = (float(v) for v in hp.object_size)
        sprite = hp.sprite_size if hp.sprite_size is not None else max(128, 2 * int(math.ceil(hi)))
        cache = ViewCache.build(hp.mesh, step_deg=hp.step_deg, sprite_size=sprite)
        frames = seedset_real_frames(seeds)
        self.train_set = SyntheticObjectDataset(
            hp.mesh, [seeds.background_frame(i) for i in train], params, mode="frame",
            real=Subset(frames, train), synthetic_per_real=hp.synthetic_per_real, object_size=(lo, hi),
            negative_fraction=hp.negative_fraction, channels=params.channels if params is not None else 1,
            seed=hp.seed, render=cache, transforms=self.train_transforms())
        self.val_set = RealFrames(Subset(frames, val)) if val else None

    def train_dataloader(self) -> DataLoader:
        from synthaug._procs import loader_worker_init
        from synthaug.data.synthetic import EpochSampler, collate_detection

        w = self.hparams.num_workers
        return DataLoader(self.train_set, batch_size=self.hparams.batch_size,
                          sampler=EpochSampler(self.train_set, shuffle=True, seed=self.hparams.seed),
                          collate_fn=collate_detection, num_workers=w, persistent_workers=w > 0,
                          worker_init_fn=loader_worker_init())

    def val_dataloader(self) -> DataLoader | list:
        from synthaug._procs import loader_worker_init
        from synthaug.data.synthetic import collate_detection

        if self.val_set is None:
            return []
        return DataLoader(self.val_set, batch_size=self.hparams.batch_size, shuffle=False,
                          collate_fn=collate_detection, num_workers=self.hparams.num_workers,
                          worker_init_fn=loader_worker_init())


# ------------------------------------------------------------------ CLI
class SaveTorchvisionWeights(L.Callback):
    """At the end of ``fit``: ``<log_dir>/detector_tv.pt`` (the model's state dict) + ``detector_tv.json`` (rank 0)."""

    def __init__(self) -> None:
        self.path: Path | None = None

    def on_fit_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        log_dir = trainer.log_dir  # a collective call under DDP: every rank makes it
        if not trainer.is_global_zero or not isinstance(pl_module, TorchvisionDetector):
            return
        out = Path(log_dir or trainer.default_root_dir)
        out.mkdir(parents=True, exist_ok=True)
        state = {k: v.detach().cpu().clone() for k, v in pl_module.detector.state_dict().items()}
        tmp = out / f".{WEIGHTS_FILE}.tmp"
        torch.save(state, tmp)
        tmp.replace(out / WEIGHTS_FILE)
        (out / ARCH_FILE).write_text(json.dumps(pl_module.arch_args, indent=1) + "\n")
        self.path = out / WEIGHTS_FILE
        print(f"torchvision detector weights saved to {self.path}")


class DetectorCLI(LightningCLI):
    """LightningCLI that always adds :class:`SaveTorchvisionWeights` (the weights file at the end of ``fit``)."""

    def instantiate_classes(self) -> None:
        super().instantiate_classes()
        if self.trainer is not None and not any(isinstance(c, SaveTorchvisionWeights) for c in self.trainer.callbacks):
            self.trainer.callbacks.append(SaveTorchvisionWeights())


def _with_subcommand(argv: list[str]) -> list[str]:
    if any(a in SUBCOMMANDS for a in argv) or argv[:1] in (["-h"], ["--help"]):
        return argv
    return ["fit", *argv]


def main(argv: list[str] | None = None, **cli_kwargs: Any) -> DetectorCLI:
    """Run the CLI on ``argv`` (default: the command line), ``fit`` when no subcommand is given.

    ``cli_kwargs`` go to LightningCLI (e.g. ``trainer_defaults={"callbacks": [...]}``).
    """
    kwargs = {"save_config_kwargs": {"overwrite": True}, **cli_kwargs}
    if argv is None:
        sys.argv[1:] = _with_subcommand(sys.argv[1:])
        return DetectorCLI(TorchvisionDetector, SyntheticFramesDataModule, **kwargs)
    return DetectorCLI(TorchvisionDetector, SyntheticFramesDataModule, args=_with_subcommand(list(argv)), **kwargs)


if __name__ == "__main__":
    main()
