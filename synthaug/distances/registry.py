"""One registry of image distances d(X_re, X_sy), chosen by name.

The paper (Rozantsev et al., §3.3) fits Θ by minimising a distance between a
real seed X_re and synthetic images X_sy *in the features of the detector*:
``eucl`` (eq. 2), ``hog`` (eq. 3), ``wl_random`` / ``wl_learned`` (eq. 5) and
``cnn`` (eq. 6). Each is a :class:`Distance` (a ``torch.nn.Module``) built by a
factory registered under its name.

Calling convention (all distances):
    ``d(x_real, x_syn) -> (B,)`` with ``x_real`` of shape ``(B, C, H, W)`` or
    ``(1, C, H, W)`` (broadcast against every synthetic image — the fitting
    loop's case: one seed, many candidates) and ``x_syn`` of shape
    ``(B, C, H, W)``, float in [0, 1]. Differentiable wherever the features are.

Distances defined in modules that may not exist yet (``wl_*``, ``cnn``) are
imported lazily on first use, see ``_LAZY_MODULES``.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any, Callable, ClassVar

import torch
from torch import Tensor

# name -> module that registers it when imported (optional modules may be absent).
_LAZY_MODULES: dict[str, str] = {
    "eucl": "synthaug.distances.basic",
    "hog": "synthaug.distances.basic",
    "wl_random": "synthaug.distances.weak_learners",
    "wl_learned": "synthaug.distances.weak_learners",
    "cnn": "synthaug.distances.cnn",
}


class Distance(torch.nn.Module):
    """Base class of an image distance ``d(x_real, x_syn) -> (B,)``.

    Most of the paper's distances are an L2 norm between feature vectors; such
    a distance only implements :meth:`features` and inherits :meth:`forward`
    (which computes the real features once when ``x_real`` has batch 1).
    Others override :meth:`compare` (weighted norms) or :meth:`forward`.

    Attributes:
        name: registry name.
        differentiable: whether gradients w.r.t. ``x_syn`` are meaningful
            (False for piecewise-constant distances such as hard weak learners).
    """

    name: ClassVar[str] = ""
    differentiable: ClassVar[bool] = True

    def features(self, x: Tensor) -> Tensor:
        """Feature vectors of a batch of images, shape ``(B, C, H, W) -> (B, D)``."""
        raise NotImplementedError(f"{type(self).__name__} does not define features(); override forward()")

    def compare(self, f_real: Tensor, f_syn: Tensor) -> Tensor:
        """Distance between feature batches (``f_real`` broadcasts), ``-> (B,)``. L2 by default."""
        return safe_norm(f_real - f_syn, dim=1)

    def forward(self, x_real: Tensor, x_syn: Tensor) -> Tensor:
        x_real, x_syn = check_pair(x_real, x_syn)
        return self.compare(self.features(x_real), self.features(x_syn))

    def extra_repr(self) -> str:
        return f"name={self.name!r}"


def safe_norm(x: Tensor, dim: int = 1) -> Tensor:
    """Euclidean norm along ``dim`` whose gradient is 0 (not NaN) at the origin.

    Example:
        >>> x = torch.zeros(2, 3, requires_grad=True)
        >>> safe_norm(x).sum().backward()
        >>> x.grad.abs().sum().item()
        0.0
    """
    sq = (x * x).sum(dim)
    positive = sq > 0
    return torch.where(positive, torch.sqrt(torch.where(positive, sq, torch.ones_like(sq))), torch.zeros_like(sq))


def check_pair(x_real: Tensor, x_syn: Tensor) -> tuple[Tensor, Tensor]:
    """Validate the ``(x_real, x_syn)`` pair of a distance call.

    Returns:
        The two tensors unchanged (``x_real`` may keep batch 1, it broadcasts).

    Raises:
        ValueError: naming the shapes, if either is not 4-D, the channel/spatial
            sizes differ, or the batch sizes neither match nor broadcast.
    """
    for name, x in (("x_real", x_real), ("x_syn", x_syn)):
        if not isinstance(x, Tensor):
            raise ValueError(f"{name} must be a torch.Tensor, got {type(x).__name__}")
        if x.dim() != 4:
            raise ValueError(f"{name} must be (B, C, H, W), got shape {tuple(x.shape)}")
        if not x.dtype.is_floating_point:
            raise ValueError(f"{name} must be a float tensor in [0, 1], got dtype {x.dtype}")
    if x_real.shape[1:] != x_syn.shape[1:]:
        raise ValueError(f"x_real and x_syn must have the same (C, H, W), got {tuple(x_real.shape)} and {tuple(x_syn.shape)}")
    if x_real.shape[0] not in (1, x_syn.shape[0]):
        raise ValueError(f"x_real batch must be 1 or match x_syn's {x_syn.shape[0]}, got {x_real.shape[0]}")
    return x_real, x_syn


@dataclass(frozen=True)
class DistanceEntry:
    """A registered distance.

    Attributes:
        name: registry name.
        factory: ``factory(**kwargs) -> Distance``.
        needs_fit: True when the factory needs data (e.g. ``wl_learned`` needs
            weak learners selected on the seeds, ``cnn`` a trained network).
        example: ``example(generator) -> Distance``, a small instance built from
            generated data, used by the generic tests and the benchmark; None
            when ``factory()`` with no arguments already works.
        doc: one line, shown by :func:`describe_distances`.
    """

    name: str
    factory: Callable[..., Distance]
    needs_fit: bool = False
    example: Callable[[torch.Generator], Distance] | None = None
    doc: str = ""


_REGISTRY: dict[str, DistanceEntry] = {}


def register_distance(
    name: str,
    *,
    needs_fit: bool = False,
    example: Callable[[torch.Generator], Distance] | None = None,
    doc: str = "",
) -> Callable[[Callable[..., Distance]], Callable[..., Distance]]:
    """Decorator registering a distance factory (a Distance subclass or a function).

    Args:
        name: registry name (``"hog"``).
        needs_fit: the factory needs fitted data passed as keyword arguments.
        example: builds a small working instance from a generator (required
            when ``needs_fit``, so that generic tests and benchmarks cover it).
        doc: one-line description (defaults to the first docstring line).

    Example:
        >>> @register_distance("l1_demo")
        ... class L1(Distance):
        ...     def forward(self, x_real, x_syn):
        ...         return (x_real - x_syn).abs().flatten(1).sum(1)
        >>> get_distance("l1_demo")(torch.zeros(1, 1, 2, 2), torch.ones(3, 1, 2, 2))
        tensor([4., 4., 4.])
        >>> unregister_distance("l1_demo")
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"distance name must be a non-empty string, got {name!r}")
    if needs_fit and example is None:
        raise ValueError(f"distance {name!r} needs_fit=True must come with an example(generator) builder")

    def decorator(factory: Callable[..., Distance]) -> Callable[..., Distance]:
        other = _REGISTRY.get(name)
        if other is not None and getattr(other.factory, "__qualname__", None) != getattr(factory, "__qualname__", None):
            raise ValueError(f"distance {name!r} is already registered by {other.factory!r}")
        first_line = (factory.__doc__ or "").strip().splitlines()
        _REGISTRY[name] = DistanceEntry(name, factory, needs_fit, example, doc or (first_line[0] if first_line else ""))
        if isinstance(factory, type) and issubclass(factory, Distance) and not factory.__dict__.get("name"):
            factory.name = name
        return factory

    return decorator


def unregister_distance(name: str) -> None:
    """Remove a distance (for tests and plug-in reloading); unknown names are ignored."""
    _REGISTRY.pop(name, None)


def _load_lazy(name: str | None = None) -> None:
    # a name we do not map (e.g. a smooth variant a module adds) may live in any of them
    modules = {_LAZY_MODULES[name]} if name in _LAZY_MODULES else set(_LAZY_MODULES.values())
    for module in sorted(modules):
        try:
            importlib.import_module(module)
        except ModuleNotFoundError as e:
            if e.name and (e.name == module or module.startswith(e.name + ".")):
                continue  # that distance's module is not part of this version
            raise


def list_distances() -> list[str]:
    """Names of all available distances (optional modules are imported to check).

    Example:
        >>> {"eucl", "hog"} <= set(list_distances())
        True
    """
    _load_lazy()
    return sorted(_REGISTRY)


def check_distance(name: str, option: str = "--distance") -> str:
    """``name`` is a registered distance (checked before a command starts working).

    Raises:
        ValueError: naming ``option`` and the registered distances.
    """
    known = list_distances()
    if name not in known:
        raise ValueError(f"{option}: unknown distance {name!r}; registered: {known}")
    return name


def get_entry(name: str) -> DistanceEntry:
    """The :class:`DistanceEntry` of a name; ValueError listing the known names."""
    if name not in _REGISTRY:
        _load_lazy(name)
    if name not in _REGISTRY:
        raise ValueError(f"unknown distance {name!r}; available: {list_distances()}")
    return _REGISTRY[name]


def get_distance(name: str, **kwargs: Any) -> Distance:
    """Build the distance registered under ``name``.

    Args:
        name: ``"eucl"``, ``"hog"``, ``"wl_random"``, ``"wl_learned"``, ``"cnn"``...
        **kwargs: passed to the distance's factory (e.g. HOG cell size, or the
            fitted weak learners of ``wl_learned``).

    Example:
        >>> d = get_distance("eucl")
        >>> d(torch.zeros(1, 1, 2, 2), torch.full((2, 1, 2, 2), 0.5))
        tensor([1., 1.])
    """
    return get_entry(name).factory(**kwargs)


def example_distance(name: str, generator: torch.Generator | None = None) -> Distance:
    """A small working instance of a distance, for generic tests and benchmarks.

    Distances that need fitting build themselves on generated data; the others
    are ``get_distance(name)``.
    """
    entry = get_entry(name)
    if entry.example is None:
        return entry.factory()
    return entry.example(generator if generator is not None else torch.Generator().manual_seed(0))


def describe_distances() -> dict[str, str]:
    """``{name: one-line doc}`` of every available distance."""
    return {name: get_entry(name).doc for name in list_distances()}
