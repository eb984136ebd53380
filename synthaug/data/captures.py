"""Capture samplers of :class:`~synthaug.data.synthetic.SyntheticObjectDataset`: where each item's Θ comes from.

The pose has its samplers (:mod:`synthaug.data.poses`); the capture parameters (every Θ column after the
five pose ones) have these. A capture sampler is any object with

- ``sample(generator, seed_index) -> tuple[float, ...] | None``: the item's own capture parameters, drawn
  from the item's ``torch.Generator`` after its noise fields and before its pose (None: the seed's own,
  nothing drawn); the tuple is :attr:`ItemParams.capture <synthaug.data.synthetic.ItemParams>`;
- ``rows(seed_indices, captures) -> CaptureParams``: the Θ rows of a batch of items, from their seeds
  ``(B,)`` and their drawn captures (the pose columns are then replaced by the items' poses).

:class:`SeedCapture` is the paper's (each item keeps its seed's Θ), :class:`KDECapture` draws from a kernel
density over the seeds (combinations no seed had), :class:`UniformCapture` draws each parameter uniform
between its min and max over the seeds (the paper's Fig. 10 baseline); the dataset's
``capture_sampling="seed" | "kde" | "uniform"`` names them.

Example:
    >>> import torch
    >>> from synthaug.params import CaptureParams
    >>> seeds = CaptureParams.sample(4, generator=torch.Generator().manual_seed(0))
    >>> SeedCapture(seeds).sample(torch.Generator(), 2) is None
    True
    >>> c = KDECapture(seeds).sample(torch.Generator().manual_seed(1), 2)
    >>> len(c), KDECapture(seeds).rows(torch.tensor([2]), [c]).batch_size
    (6, 1)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import torch

from synthaug.data.density import CaptureDensity
from synthaug.params import CaptureParams

__all__ = ["CaptureSampler", "SeedCapture", "KDECapture", "UniformCapture", "CAPTURE_SAMPLERS"]


@runtime_checkable
class CaptureSampler(Protocol):
    """What :class:`~synthaug.data.synthetic.SyntheticObjectDataset` calls to draw and use an item's Θ."""

    def sample(self, generator: torch.Generator, seed_index: int) -> tuple[float, ...] | None:
        """The item's capture parameters (None: its seed's own)."""
        ...

    def rows(self, seed_indices: torch.Tensor, captures: Sequence[tuple[float, ...] | None]) -> CaptureParams:
        """The Θ rows of a batch of items."""
        ...


class SeedCapture:
    """Each item keeps its seed's capture parameters (the paper).

    Args:
        params: Θ of the seeds, one row per seed.
    """

    def __init__(self, params: CaptureParams) -> None:
        self.params = params

    def sample(self, generator: torch.Generator, seed_index: int) -> None:
        """Nothing to draw: the seed's row is the item's."""
        return None

    def rows(self, seed_indices: torch.Tensor, captures: Sequence[tuple[float, ...] | None]) -> CaptureParams:
        """The seeds' rows."""
        return self.params[seed_indices]

    def __repr__(self) -> str:
        return f"SeedCapture({self.params.batch_size} seeds)"


class _DensityCapture:
    """Capture parameters drawn from a :class:`~synthaug.data.density.CaptureDensity` over the seeds."""

    kind: str

    def __init__(self, params: CaptureParams) -> None:
        self.density = CaptureDensity(params, kind=self.kind)  # type: ignore[arg-type]

    def sample(self, generator: torch.Generator, seed_index: int) -> tuple[float, ...]:
        """One draw of the density (the seed is not used: the density spans all seeds)."""
        return tuple(self.density.sample(1, generator=generator)[0].tolist())

    def rows(self, seed_indices: torch.Tensor, captures: Sequence[tuple[float, ...] | None]) -> CaptureParams:
        """The drawn captures as Θ rows (pose columns zero)."""
        return self.density.to_params(torch.tensor(captures, dtype=torch.float64))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.density!r})"


class KDECapture(_DensityCapture):
    """Capture parameters from a Gaussian kernel density over the seeds (combinations no seed had).

    Args:
        params: Θ of the seeds (at least 2; the pose columns are ignored).
    """

    kind = "kde"


class UniformCapture(_DensityCapture):
    """Each capture parameter uniform between its min and max over the seeds (the paper's Fig. 10 baseline).

    Args:
        params: Θ of the seeds (at least 2; the pose columns are ignored).
    """

    kind = "uniform"


CAPTURE_SAMPLERS: dict[str, type] = {"seed": SeedCapture, "kde": KDECapture, "uniform": UniformCapture}
"""The names ``SyntheticObjectDataset(capture_sampling=...)`` accepts, and the sampler each builds."""
