"""Pose samplers of :class:`~synthaug.data.synthetic.SyntheticObjectDataset`: how each item's pose is drawn.

A pose sampler is any object with ``sample(generator, seed_index, u) -> {"alpha", "beta", "gamma", "t_x",
"t_y"}`` (radians; t_x, t_y as :data:`synthaug.params.POSE_SPECS`):

- ``u``: five uniforms in [0, 1), one per pose parameter in :data:`~synthaug.params.POSE_NAMES` order, drawn
  among the item's first draws (a sampler that wants uniform values maps them; it need not use them);
- ``generator``: the item's ``torch.Generator`` *after* all its other draws (background patch, noise fields,
  capture parameters), so a sampler may draw more from it without moving any other draw;
- ``seed_index``: the seed whose background and capture parameters the item uses.

:class:`UniformPose` is the paper's draw (every view equally likely), :class:`FittedPose` draws around each
seed's fitted rotation, and :class:`SeedOffset` puts the object where its seed's object was (the seed's fitted
t_x, t_y) whatever another sampler draws for the rotation. All are pure functions of their arguments.
:data:`POSE_SAMPLING` names the choices a string can make (:func:`pose_sampler` builds them).

Example:
    >>> import torch
    >>> pose = UniformPose({"beta": (-0.2, 0.2)}).sample(torch.Generator(), 0, [0.5] * 5)
    >>> round(pose["beta"], 6), sorted(pose)
    (0.0, ['alpha', 'beta', 'gamma', 't_x', 't_y'])
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from typing import Any, Protocol, runtime_checkable

import numpy as np
import torch
from scipy.spatial.transform import Rotation

from synthaug.params import POSE_NAMES, POSE_SPECS, CaptureParams
from synthaug.render.pose import rotation_matrix

__all__ = ["PoseSampler", "UniformPose", "FittedPose", "SeedOffset", "POSE_SAMPLING", "pose_sampler", "pose_ranges",
           "jittered_pose"]

POSE_SAMPLING: tuple[str, ...] = ("uniform", "fitted", "uniform_at_seed", "fitted_at_seed")
"""The pose samplings a string names: the rotation ``uniform`` (:class:`UniformPose`) or ``fitted`` (around each
seed's fitted rotation, :class:`FittedPose` with its default jitter); ``_at_seed``: the object placed at its seed's
fitted offset (:class:`SeedOffset`) instead of t_x, t_y drawn uniformly."""

_ROTATION = ("alpha", "beta", "gamma")


@runtime_checkable
class PoseSampler(Protocol):
    """What :class:`~synthaug.data.synthetic.SyntheticObjectDataset` calls to draw an item's pose."""

    def sample(self, generator: torch.Generator, seed_index: int, u: Sequence[float]) -> dict[str, float]:
        """One pose ``{name: value}`` for every name of :data:`~synthaug.params.POSE_NAMES`."""
        ...


def pose_ranges(overrides: Mapping[str, tuple[float, float]] | None = None) -> dict[str, tuple[float, float]]:
    """The pose sampling ranges (α, β, γ, t_x, t_y): the defaults of :data:`~synthaug.params.POSE_SPECS`
    with ``overrides`` checked and applied."""
    ranges = {s.name: s.sampling_range for s in POSE_SPECS}
    for k, v in dict(overrides or {}).items():
        if k not in ranges:
            raise ValueError(f"pose_ranges: unknown pose parameter {k!r}; known: {list(POSE_NAMES)}")
        lo, hi = float(v[0]), float(v[1])
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ValueError(f"pose_ranges[{k!r}] must be finite (low, high) with low <= high, got {v}")
        ranges[k] = (lo, hi)
    return ranges


def jittered_pose(alpha: float, beta: float, gamma: float, rotvec: np.ndarray) -> tuple[float, float, float]:
    """The Euler angles of ``R(α, β, γ) · exp([rotvec]×)``: a pose turned by a small rotation in the object's frame.

    ``R = Rz(γ) Ry(β) Rx(α)`` (:func:`synthaug.render.pose.rotation_matrix`); the rotation of
    rotation vector ``rotvec`` (axis · angle, radians) is applied first, in the object's own
    frame, so the jitter does not depend on where the pose sits in Euler angles (no gimbal bias).
    Returns ``(α, β, γ)`` with α, γ in (-π, π] and β in [-π/2, π/2].
    """
    r = rotation_matrix(alpha, beta, gamma) @ Rotation.from_rotvec(np.asarray(rotvec, dtype=np.float64)).as_matrix()
    b = math.asin(max(-1.0, min(1.0, -r[2, 0])))
    a = math.atan2(r[2, 1], r[2, 2])
    c = math.atan2(r[1, 0], r[0, 0])
    return a, b, c


class UniformPose:
    """Every pose parameter uniform over its range (the paper: every view equally likely).

    Args:
        ranges: overrides of the default sampling ranges, ``{name: (low, high)}`` (see :func:`pose_ranges`).
    """

    def __init__(self, ranges: Mapping[str, tuple[float, float]] | None = None) -> None:
        self.ranges = pose_ranges(ranges)

    def sample(self, generator: torch.Generator, seed_index: int, u: Sequence[float]) -> dict[str, float]:
        """``low + (high - low) · u`` per parameter; draws nothing from ``generator``."""
        return {name: lo + (hi - lo) * u[k] for k, name in enumerate(POSE_NAMES) for lo, hi in [self.ranges[name]]}

    def __repr__(self) -> str:
        return f"UniformPose(ranges={self.ranges})"


class FittedPose:
    """Each seed's fitted rotation turned by a random rotation; t_x, t_y uniform as :class:`UniformPose`.

    The random rotation has a rotation vector ~ N(0, jitter² I₃) (axis uniform on the sphere), applied in the
    object's frame (:func:`jittered_pose`): the views the real seeds show, and views near them.

    Args:
        rotations: the fitted rotations, one per seed: anything with ``alpha``, ``beta``, ``gamma`` rows (a
            :class:`~synthaug.params.CaptureParams` from a fit), the path of a fit file (``synthaug fit``'s
            output) or an ``(N, 3)`` array of (α, β, γ) radians.
        jitter_deg: spread of the random rotation, degrees per component of its rotation vector (0: the
            fitted rotation itself).
        ranges: overrides of the t_x, t_y (and unused α, β, γ) sampling ranges (see :func:`pose_ranges`).
    """

    def __init__(self, rotations: Any, jitter_deg: float = 20.0,
                 ranges: Mapping[str, tuple[float, float]] | None = None) -> None:
        rows = _fitted_rows(rotations, _ROTATION)
        if not (math.isfinite(jitter_deg) and jitter_deg >= 0):
            raise ValueError(f"jitter_deg must be finite and >= 0, got {jitter_deg}")
        self.rotations: list[tuple[float, ...]] = rows
        self.jitter_deg = float(jitter_deg)
        self._uniform = UniformPose(ranges)

    def sample(self, generator: torch.Generator, seed_index: int, u: Sequence[float]) -> dict[str, float]:
        """t_x, t_y from ``u``; α, β, γ: the seed's rotation jittered by three normal draws from ``generator``."""
        pose = self._uniform.sample(generator, seed_index, u)
        rotvec = torch.randn(3, generator=generator, dtype=torch.float64).numpy() * math.radians(self.jitter_deg)
        pose.update(zip(_ROTATION, jittered_pose(*self.rotations[seed_index], rotvec)))
        return pose

    def __repr__(self) -> str:
        return f"FittedPose({len(self.rotations)} seeds, jitter_deg={self.jitter_deg})"


def _fitted_rows(fit: Any, names: Sequence[str]) -> list[tuple[float, ...]]:
    """One row of the ``names`` fields per seed from a fit (its file, a CaptureParams) or an (N, len(names)) array."""
    if isinstance(fit, (str, os.PathLike)):
        fit = CaptureParams.load(fit)
    if all(hasattr(fit, n) for n in names):
        rows = list(zip(*([float(v) for v in getattr(fit, n)] for n in names)))
    else:
        a = np.asarray(fit, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != len(names):
            raise ValueError(f"give a fit with {'/'.join(names)} rows or an (N, {len(names)}) array, "
                             f"got shape {a.shape}")
        rows = [tuple(float(v) for v in r) for r in a]
    if not all(math.isfinite(v) for r in rows for v in r):
        raise ValueError(f"the fitted {'/'.join(names)} must be finite")
    return rows


class SeedOffset:
    """Another sampler's rotation, with the object placed where its seed's object was: the seed's fitted t_x, t_y.

    The background of a synthetic item is its seed's, with the real object inpainted away. A uniform t_x, t_y
    moves the rendered object off that inpainted area and shows it; at the fitted offset the object covers it, as
    the real object did. Measured on the drones (100 seeds, ``results/synthetic/placement/``): the training
    positives are told from the real seed patches 0.00-0.05 less often in HOG features, but detectors trained on them
    lose AP (HOG -0.015, the CNN -0.019 against uniform offsets), so the library's default keeps the uniform draw.

    Args:
        sampler: the pose sampler whose rotation is kept (e.g. :class:`UniformPose`, :class:`FittedPose`).
        offsets: each seed's offset: anything with ``t_x``, ``t_y`` rows (a fit's
            :class:`~synthaug.params.CaptureParams`), a fit file or an ``(N, 2)`` array (fractions of the patch side).

    Example:
        >>> import torch
        >>> s = SeedOffset(UniformPose(), [[0.05, -0.02], [0.0, 0.1]])
        >>> p = s.sample(torch.Generator(), 1, [0.5] * 5)
        >>> round(p["t_x"], 6), round(p["t_y"], 6), round(p["beta"], 6)
        (0.0, 0.1, 0.0)
    """

    def __init__(self, sampler: Any, offsets: Any) -> None:
        if not callable(getattr(sampler, "sample", None)):
            raise ValueError(f"sampler must be a pose sampler (an object with sample(generator, seed_index, u)), "
                             f"got {type(sampler).__name__}")
        self.sampler = sampler
        self.offsets: list[tuple[float, ...]] = _fitted_rows(offsets, ("t_x", "t_y"))
        rotations = getattr(sampler, "rotations", None)
        if rotations is not None and len(rotations) != len(self.offsets):
            raise ValueError(f"{len(self.offsets)} offsets but the sampler holds {len(rotations)} rotations "
                             f"(one of each per seed)")

    def __len__(self) -> int:
        return len(self.offsets)

    def sample(self, generator: torch.Generator, seed_index: int, u: Sequence[float]) -> dict[str, float]:
        """The wrapped sampler's pose (its draws from ``generator`` unchanged) with t_x, t_y the seed's offset."""
        pose = dict(self.sampler.sample(generator, seed_index, u))
        pose["t_x"], pose["t_y"] = self.offsets[seed_index]
        return pose

    def __repr__(self) -> str:
        return f"SeedOffset({self.sampler!r}, {len(self.offsets)} seeds)"


def pose_sampler(name: str, params: Any = None) -> Any:
    """The sampler a :data:`POSE_SAMPLING` name stands for; ``params``: the fit (needed by all but ``"uniform"``).

    Example:
        >>> pose_sampler("uniform_at_seed", [[0.0, 0.0, 0.0, 0.1, -0.1]] * 2).__class__.__name__
        'SeedOffset'
    """
    if name not in POSE_SAMPLING:
        raise ValueError(f"pose_sampling must be one of {', '.join(map(repr, POSE_SAMPLING))} or a pose sampler "
                         f"(an object with sample(generator, seed_index, u)), got {name!r}")
    if name == "uniform":
        return UniformPose()
    if params is None:
        raise ValueError(f"pose_sampling={name!r} draws from each seed's fitted pose: give params (a fit)")
    rows = np.asarray(_fitted_rows(params, POSE_NAMES))  # α, β, γ, t_x, t_y per seed
    inner = FittedPose(rows[:, :3]) if name.startswith("fitted") else UniformPose()
    return SeedOffset(inner, rows[:, 3:]) if name.endswith("_at_seed") else inner
