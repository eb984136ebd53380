"""The two feature-free-of-training distances: ``eucl`` (eq. 2) and ``hog`` (eq. 3).

Example:
    >>> import torch
    >>> g = torch.Generator().manual_seed(0)
    >>> real = torch.rand(1, 1, 40, 40, generator=g)
    >>> syn = torch.rand(4, 1, 40, 40, generator=g)
    >>> EuclideanDistance()(real, syn).shape, HOGDistance()(real, syn).shape
    (torch.Size([4]), torch.Size([4]))
"""

from __future__ import annotations

from torch import Tensor

from synthaug.detectors.hog import DEFAULT_HOG, HOGConfig, hog
from synthaug.distances.registry import Distance, register_distance


@register_distance("eucl", doc="pixel L2, eq. 2: sqrt(sum_uv (X_re(u,v) - X_sy(u,v))^2)")
class EuclideanDistance(Distance):
    """Pixel-wise Euclidean distance d_Eucl (eq. 2 of the paper).

    ``d(X_re, X_sy) = sqrt(Σ_{u,v} (X_re(u, v) - X_sy(u, v))²)``, summed over
    channels too. Not normalised by the number of pixels, as in the paper.

    Example:
        >>> import torch
        >>> EuclideanDistance()(torch.zeros(1, 1, 3, 3), torch.full((1, 1, 3, 3), 1 / 3))
        tensor([1.])
    """

    def features(self, x: Tensor) -> Tensor:
        return x.flatten(1)


@register_distance("hog", doc="L2 between HOG vectors, eq. 3 (8-px cells, 2x2 blocks, 9 bins, L2-Hys)")
class HOGDistance(Distance):
    """L2 distance between HOG descriptors d_HoG (eq. 3 of the paper).

    ``d(X_re, X_sy) = sqrt(Σ_i (HoG_i(X_re) - HoG_i(X_sy))²)`` with the HOG of
    :func:`synthaug.detectors.hog.hog` — the features the HOG detector uses, so
    fitting Θ with this distance makes synthetic images look real to it.

    Args:
        config: HOG settings; the default has soft orientation binning, which is
            smooth in the gradient angle (use ``SKIMAGE_HOG`` for hard bins).
    """

    def __init__(self, config: HOGConfig = DEFAULT_HOG) -> None:
        super().__init__()
        if not isinstance(config, HOGConfig):
            raise ValueError(f"config must be a HOGConfig, got {type(config).__name__}")
        self.config = config

    def features(self, x: Tensor) -> Tensor:
        return hog(x, self.config)

    def extra_repr(self) -> str:
        return f"name={self.name!r}, config={self.config}"
