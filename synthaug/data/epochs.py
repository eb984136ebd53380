"""Every item a pure function of ``(seed, epoch, index)``: its seed, its generator, and the sampler that carries
the epoch to the DataLoader workers.

:func:`item_seed` hashes ``(seed, epoch, index)`` into a 64-bit seed (a splitmix64 chain) and
:func:`item_generator` is the ``torch.Generator`` seeded with it, so the worker count never changes the data.
:class:`EpochSampler` yields ``(epoch, index)`` pairs: the epoch travels with each index, also to persistent
workers (:class:`~synthaug.data.synthetic.SyntheticObjectDataset` draws new poses every epoch).

Example:
    >>> item_seed(0, 0, 1) == item_seed(0, 0, 1) != item_seed(0, 1, 1)
    True
    >>> s = EpochSampler(3)
    >>> s.set_epoch(1)
    >>> list(s)
    [(1, 0), (1, 1), (1, 2)]
"""

from __future__ import annotations

from typing import Any

import torch
from torch.utils.data import Sampler

__all__ = ["EpochSampler", "item_generator", "item_seed"]

_MASK64 = (1 << 64) - 1


def _splitmix64(x: int) -> int:
    x = (x + 0x9E3779B97F4A7C15) & _MASK64
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & _MASK64
    return x ^ (x >> 31)


def item_seed(seed: int, epoch: int, index: int) -> int:
    """64-bit seed of one item: splitmix64 hash chain of (seed, epoch, index).

    (numpy's SeedSequence does the same job but costs ~0.1 ms per call, a
    tenth of the time budget of a sample.)
    """
    return _splitmix64(_splitmix64(_splitmix64(int(seed) & _MASK64) ^ (int(epoch) & _MASK64)) ^ (int(index) & _MASK64))


def item_generator(seed: int, epoch: int, index: int) -> torch.Generator:
    """The generator of one item: a pure function of (seed, epoch, index)."""
    return torch.Generator().manual_seed(item_seed(seed, epoch, index))


class EpochSampler(Sampler):
    """Yields ``(epoch, index)`` pairs: the epoch travels with each index to the worker.

    A ``DataLoader`` with ``persistent_workers=True`` keeps copies of the
    dataset in its workers, so :meth:`SyntheticObjectDataset.set_epoch` on the
    main-process dataset never reaches them. The sampler lives in the main
    process and its ``set_epoch`` (called by Lightning's loops and by
    ``DistributedSampler`` users) changes the indices themselves.

    Args:
        source: the dataset (or its length) to draw indices over, or any
            sampler of integer indices to wrap (e.g. a ``DistributedSampler``;
            its ``set_epoch`` is called too).
        shuffle: a fresh permutation every epoch (own sampling only), drawn
            from ``torch.Generator().manual_seed(item_seed(seed, epoch, -1))``.
        seed: seeds the permutations.

    Example:
        >>> s = EpochSampler(4)
        >>> s.set_epoch(2)
        >>> list(s)
        [(2, 0), (2, 1), (2, 2), (2, 3)]
        >>> s = EpochSampler(5, shuffle=True, seed=1)
        >>> sorted(i for _, i in s) == [0, 1, 2, 3, 4]
        True
    """

    def __init__(self, source: Any, *, shuffle: bool = False, seed: int = 0) -> None:
        if isinstance(source, Sampler) or (not isinstance(source, int) and not hasattr(source, "__getitem__")
                                           and hasattr(source, "__iter__")):
            if shuffle:
                raise ValueError("shuffle=True is for EpochSampler's own sampling; the wrapped sampler decides "
                                 "its own order")
            self.sampler: Any = source
            self.n = None
        else:
            n = int(source) if isinstance(source, int) else len(source)
            if n < 0:
                raise ValueError(f"EpochSampler needs a length >= 0, got {n}")
            self.sampler = None
            self.n = n
        self.shuffle = bool(shuffle)
        self.seed = int(seed)
        self.epoch = 0

    def set_epoch(self, epoch: int) -> None:
        """The epoch that the next iteration carries (and the wrapped sampler's)."""
        self.epoch = int(epoch)
        if self.sampler is not None and hasattr(self.sampler, "set_epoch"):
            self.sampler.set_epoch(epoch)

    def __len__(self) -> int:
        return len(self.sampler) if self.sampler is not None else self.n  # type: ignore[arg-type]

    def __iter__(self):
        epoch = self.epoch
        if self.sampler is not None:
            order = (int(i) for i in self.sampler)
        elif self.shuffle:
            g = torch.Generator().manual_seed(item_seed(self.seed, epoch, -1))
            order = iter(torch.randperm(self.n, generator=g).tolist())
        else:
            order = iter(range(self.n))
        for i in order:
            yield (epoch, i)
