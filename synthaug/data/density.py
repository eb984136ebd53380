"""Densities over the fitted capture parameters, to create combinations no seed had.

The paper keeps each seed's capture parameters and notes that their joint
distribution is "absolutely not Gaussian". :class:`CaptureDensity` offers:

- ``"kde"``: a Gaussian kernel density estimate over all seeds (Scott's
  bandwidth, the same kernel covariance as ``scipy.stats.gaussian_kde``),
  sampled as KDEs are: pick a seed at random, add kernel noise; values are
  folded back into range (periodic angles wrap, others reflect at the bounds);
- ``"uniform"``: each parameter uniform between its min and max over the seeds
  (the paper's Fig. 10 baseline against which fitting is compared).

Sampling uses an explicit ``torch.Generator`` (no global RNG).

Example:
    >>> import torch
    >>> from synthaug.params import CaptureParams
    >>> seeds = CaptureParams.sample(30, generator=torch.Generator().manual_seed(0))
    >>> dens = CaptureDensity(seeds, kind="kde")
    >>> dens.sample(5, generator=torch.Generator().manual_seed(1)).shape
    torch.Size([5, 6])
"""

from __future__ import annotations

import math
from typing import Literal

import torch

from synthaug.params import CaptureParams, effect_param_specs

Kind = Literal["kde", "uniform"]


class CaptureDensity:
    """A density over the capture columns (all Θ columns after the 5 pose ones).

    Args:
        params: fitted Θ of the seeds (pose columns are ignored).
        kind: ``"kde"`` or ``"uniform"``.
        bandwidth: KDE bandwidth factor; None = Scott's rule ``n^(-1/(d+4))``.
    """

    def __init__(self, params: CaptureParams, *, kind: Kind = "kde", bandwidth: float | None = None) -> None:
        if kind not in ("kde", "uniform"):
            raise ValueError(f"kind must be 'kde' or 'uniform', got {kind!r}")
        if params.batch_size < 2:
            raise ValueError(f"a density needs at least 2 seeds, got {params.batch_size}")
        self.kind = kind
        self.channels = params.channels
        self.effects = params.effects
        data = params.to_vector().double()[:, 5:]
        self.data = data
        lo, hi, per = [], [], []
        for s in effect_param_specs(params.effects):
            k = params.channels if s.per_channel else 1
            lo += [s.low] * k
            hi += [s.high] * k
            per += [s.periodic] * k
        self.low, self.high = torch.tensor(lo, dtype=torch.float64), torch.tensor(hi, dtype=torch.float64)
        self.periodic = torch.tensor(per)
        self.data_min, self.data_max = data.min(0).values, data.max(0).values
        n, d = data.shape
        self.factor = bandwidth if bandwidth is not None else n ** (-1.0 / (d + 4))
        cov = torch.cov(data.T) if n > 1 else torch.zeros(d, d, dtype=torch.float64)
        self.kernel_cov = cov * self.factor ** 2
        # constant columns (e.g. an effect fitted to 0 everywhere) have no spread: jitter for Cholesky
        self._chol = torch.linalg.cholesky(self.kernel_cov + 1e-12 * torch.eye(d, dtype=torch.float64))

    @property
    def dim(self) -> int:
        return int(self.data.shape[1])

    def sample(self, n: int, *, generator: torch.Generator) -> torch.Tensor:
        """(n, D) capture columns (float64), in the order of ``CaptureParams.to_vector()[:, 5:]``."""
        if self.kind == "uniform":
            u = torch.rand(n, self.dim, generator=generator, dtype=torch.float64)
            return self.data_min + (self.data_max - self.data_min) * u
        idx = torch.randint(self.data.shape[0], (n,), generator=generator)
        z = torch.randn(n, self.dim, generator=generator, dtype=torch.float64)
        x = self.data[idx] + z @ self._chol.T
        return self._fold(x)

    def _fold(self, x: torch.Tensor) -> torch.Tensor:
        span = self.high - self.low
        wrapped = torch.remainder(x - self.low, span) + self.low
        # reflect at the bounds: period 2·span triangle wave
        t = torch.remainder(x - self.low, 2 * span)
        reflected = self.low + torch.where(t > span, 2 * span - t, t)
        return torch.where(self.periodic, wrapped, reflected)

    def to_params(self, capture: torch.Tensor, pose: dict[str, torch.Tensor] | None = None) -> CaptureParams:
        """Capture columns (+ optional pose) -> :class:`CaptureParams`."""
        n = capture.shape[0]
        pose_cols = torch.zeros(n, 5, dtype=torch.float64)
        if pose:
            for j, name in enumerate(("alpha", "beta", "gamma", "t_x", "t_y")):
                if name in pose:
                    pose_cols[:, j] = torch.as_tensor(pose[name], dtype=torch.float64)
        return CaptureParams.from_vector(torch.cat([pose_cols, capture], 1), channels=self.channels,
                                         effects=self.effects, validate=False)

    def __repr__(self) -> str:
        return f"CaptureDensity(kind={self.kind!r}, seeds={self.data.shape[0]}, dim={self.dim}, factor={self.factor:.3f})"


def scott_factor(n: int, d: int) -> float:
    return n ** (-1.0 / (d + 4)) if n > 0 else math.nan
