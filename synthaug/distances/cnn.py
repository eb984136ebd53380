"""The CNN distance d_CNN (eq. 6 of the paper): L2 over the activations of layers 2..N.

    d_CNN(X_re, X_sy) = sqrt(Σ_{n=2}^{N} Σ_i (CNN_i^n(X_re) - CNN_i^n(X_sy))²)

CNN_i^n the i-th neuron of layer n of a :class:`~synthaug.detectors.cnn.PatchCNN`
"trained on the real seed images only". The network is given directly, loaded
from a checkpoint (``save_detector`` file or Lightning ``.ckpt``), or trained
here on seed positives/negatives with :func:`~synthaug.detectors.lightning_module.train_patch_cnn`
(the project's one CNN training loop: ``PatchDetectorModule`` under ``lightning.Trainer``).

Differentiable in the synthetic image (ReLU / max-pool subgradients); the
network's own parameters are frozen. With a single real image (the fitting
loop's case) its activations are computed once per call.

Example:
    >>> import torch
    >>> from synthaug.detectors.cnn import PatchCNN
    >>> d = CNNDistance(PatchCNN(generator=torch.Generator().manual_seed(0)))
    >>> x = torch.rand(4, 1, 40, 40, generator=torch.Generator().manual_seed(1))
    >>> d(x[:1], x).shape, float(d(x, x).max())
    (torch.Size([4]), 0.0)
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import torch
from torch import Tensor

from synthaug.detectors.cnn import PatchCNN, load_patch_cnn
from synthaug.detectors.lightning_module import train_patch_cnn
from synthaug.distances.registry import Distance, register_distance

__all__ = ["CNNDistance", "cnn_distance"]


class CNNDistance(Distance):
    """L2 distance between the concatenated activations of layers ``first_layer..N``.

    Args:
        net: the (trained) network; it is put in eval mode and frozen.
        first_layer: first layer counted (the paper: 2); 1-based, <= N = 5.

    Shape:
        - x_real: (B, 1, w, w) or (1, 1, w, w); x_syn: (B, 1, w, w), w = net.window
        - output: (B,)
    """

    def __init__(self, net: PatchCNN, first_layer: int = 2) -> None:
        super().__init__()
        if not isinstance(net, PatchCNN):
            raise ValueError(f"net must be a PatchCNN, got {type(net).__name__}")
        if not isinstance(first_layer, int) or not 1 <= first_layer <= 5:
            raise ValueError(f"first_layer must be an int in [1, 5], got {first_layer}")
        self.net = net.eval()
        for p in self.net.parameters():
            p.requires_grad_(False)
        self.first_layer = first_layer

    def train(self, mode: bool = True) -> "CNNDistance":
        super().train(mode)
        self.net.eval()  # the distance is a fixed feature map, whatever the caller's mode
        return self

    def features(self, x: Tensor) -> Tensor:
        w = self.net.window
        if x.shape[1] != 1 or x.shape[-2:] != (w, w):
            raise ValueError(f"the cnn distance takes (B, 1, {w}, {w}) patches, got {tuple(x.shape)}")
        acts = self.net.layer_activations(x)[self.first_layer - 1:]
        return torch.cat([a.flatten(1) for a in acts], dim=1)

    def extra_repr(self) -> str:
        return f"name={self.name!r}, layers={self.first_layer}..5, channels={self.net.channels}"


def _example(generator: torch.Generator) -> CNNDistance:
    # an untrained, seeded network: enough for the metric properties and for timing
    return CNNDistance(PatchCNN(generator=generator))


@register_distance("cnn", needs_fit=True, example=_example,
                   doc="L2 over activations of layers 2..N of a CNN trained on the seeds (d_CNN, eq. 6)")
def cnn_distance(
    net: PatchCNN | None = None,
    checkpoint: str | Path | None = None,
    positives: Tensor | None = None,
    negatives: Tensor | None = None,
    channels: Sequence[int] = (8, 16, 32, 64),
    epochs: int = 15,
    seed: int = 0,
    first_layer: int = 2,
) -> CNNDistance:
    """d_CNN from a network, a checkpoint, or seeds to train one on (exactly one source).

    Args:
        net: a trained :class:`PatchCNN`.
        checkpoint: a ``save_detector`` CNN file or a ``PatchDetectorModule`` Lightning checkpoint.
        positives: real seed patches ``(P, 1, 40, 40)``; with ``negatives``, a
            network is trained here (:func:`train_patch_cnn`, ``epochs``, ``seed``).
        negatives: background patches ``(N, 1, 40, 40)``.
        channels: network width when training here.
        epochs: training epochs when training here.
        seed: training seed when training here.
        first_layer: first layer of the sum (2 in the paper).
    """
    given = [net is not None, checkpoint is not None, positives is not None or negatives is not None]
    if sum(given) != 1:
        raise ValueError("the cnn distance needs exactly one of net=, checkpoint= or positives= and negatives=, got "
                         f"net={net is not None}, checkpoint={checkpoint!r}, "
                         f"positives/negatives={positives is not None}/{negatives is not None}")
    if checkpoint is not None:
        net = load_patch_cnn(checkpoint)
    elif net is None:
        if positives is None or negatives is None:
            raise ValueError("the cnn distance needs both positives= and negatives= to train a network")
        net = train_patch_cnn(positives, negatives, channels=channels, epochs=epochs, seed=seed)
    return CNNDistance(net, first_layer=first_layer)
