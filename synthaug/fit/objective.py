"""The fitting objective d(X_i, S(Θ, B_i)), batched over candidate Θ's.

Optimisers search a box ``u ∈ [0, 1]^D``; :class:`FitSpace` maps it to Θ
(pose + capture parameters) and back. :class:`RenderObjective` renders a whole
population of candidates in one torch pass (view cache + effects) and scores
it with a registered distance: this is what makes population optimisers such
as CMA-ES fast here.

Randomness: the object-noise field is drawn once per seed (common random
numbers), so the objective is a deterministic function of Θ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import torch

from synthaug.effects.pipeline import sample_fields, simulate
from synthaug.params import POSE_SPECS, CaptureParams, effect_param_specs, resolve_effect_names


@dataclass(frozen=True)
class FitSpace:
    """Free Θ columns, their search bounds, and the map ``u ∈ [0, 1]^D -> Θ``.

    Periodic angles (α, γ, α_m) wrap, so the optimiser may leave [0, 1] on those.

    Attributes:
        names: column names of ``CaptureParams.to_vector`` (all of them).
        low, high: search bounds per column.
        free: mask of columns the optimiser moves; the others stay at ``fixed``.
        fixed: values of the non-free columns.
        periodic: mask of wrapping columns.
    """

    names: tuple[str, ...]
    low: np.ndarray
    high: np.ndarray
    free: np.ndarray
    fixed: np.ndarray
    periodic: np.ndarray
    channels: int
    effects: tuple[str, ...]
    scale_range: tuple[float, float] | None = None

    # With ``scale_range`` (an extension of the paper's Θ), one more search
    # coordinate, the last, sets the object scale log-uniformly in that range:
    # real boxes are often loose (the object fills much less of the patch than
    # the box says), and a fixed scale then cannot match the seed.

    @classmethod
    def default(
        cls,
        *,
        channels: int = 1,
        effects: Sequence[str] | None = None,
        translation: float = 0.15,
        bounds: dict[str, tuple[float, float]] | None = None,
        fixed: dict[str, float] | None = None,
        scale_range: tuple[float, float] | None = None,
    ) -> "FitSpace":
        """Θ with every field free within its spec range; t_x, t_y within ±``translation``
        (the annotated centre is the patch centre). ``fixed`` pins fields (e.g. to
        switch an effect's parameters off), ``bounds`` narrows ranges."""
        eff = resolve_effect_names(effects)
        specs = POSE_SPECS + effect_param_specs(eff)
        names, low, high, per = [], [], [], []
        for s in specs:
            k = channels if s.per_channel else 1
            lo, hi = s.low, s.high
            if s.name in ("t_x", "t_y"):
                lo, hi = -translation, translation
            if bounds and s.name in bounds:
                lo, hi = bounds[s.name]
            for c in range(k):
                names.append(f"{s.name}[{c}]" if k > 1 else s.name)
                low.append(lo)
                high.append(hi)
                per.append(s.periodic)
        n = len(names)
        free = np.ones(n, bool)
        fixed_v = np.zeros(n)
        for key, value in dict(fixed or {}).items():
            cols = [i for i, nm in enumerate(names) if nm == key or nm.startswith(key + "[")]
            if not cols:
                raise ValueError(f"fixed: unknown parameter {key!r}")
            free[cols] = False
            fixed_v[cols] = value
        unknown = sorted(set(bounds or {}) - {s.name for s in specs})
        if unknown:
            raise ValueError(f"bounds: unknown parameter(s) {unknown}")
        if scale_range is not None and not (0 < scale_range[0] <= scale_range[1]):
            raise ValueError(f"scale_range must be (low, high) with 0 < low <= high, got {scale_range}")
        return cls(tuple(names), np.array(low, float), np.array(high, float), free, fixed_v,
                   np.array(per, bool), channels, eff,
                   None if scale_range is None else (float(scale_range[0]), float(scale_range[1])))

    @property
    def dim(self) -> int:
        return int(self.free.sum()) + (self.scale_range is not None)

    @property
    def theta_dim(self) -> int:
        return int(self.free.sum())

    def scale(self, u: np.ndarray | torch.Tensor, default: float) -> torch.Tensor:
        """Object scale of each candidate: the last coordinate (log-uniform) or ``default``."""
        u = u.double() if isinstance(u, torch.Tensor) else torch.as_tensor(np.asarray(u, dtype=np.float64))
        u = u[None] if u.ndim == 1 else u
        if self.scale_range is None:
            return torch.full((u.shape[0],), float(default), dtype=torch.float64)
        lo, hi = self.scale_range
        return torch.exp(math.log(lo) + (math.log(hi) - math.log(lo)) * u[:, -1].clamp(0.0, 1.0))

    def scale_to_u(self, scale: float) -> float:
        lo, hi = self.scale_range  # type: ignore[misc]
        return float(np.clip((math.log(scale) - math.log(lo)) / (math.log(hi) - math.log(lo) or 1.0), 0.0, 1.0))

    def to_vector(self, u: np.ndarray | torch.Tensor) -> torch.Tensor:
        """(N, D) search coordinates -> (N, P) Θ vectors (float64)."""
        u = torch.as_tensor(np.asarray(u, dtype=np.float64)) if not isinstance(u, torch.Tensor) else u.double()
        if u.ndim == 1:
            u = u[None]
        if u.shape[1] != self.dim:
            raise ValueError(f"expected (N, {self.dim}) search coordinates, got {tuple(u.shape)}")
        u = u[:, : self.theta_dim]
        per = torch.as_tensor(self.periodic[self.free])
        u = torch.where(per, torch.remainder(u, 1.0), u.clamp(0.0, 1.0))
        lo = torch.as_tensor(self.low[self.free])
        hi = torch.as_tensor(self.high[self.free])
        v = torch.as_tensor(self.fixed).repeat(u.shape[0], 1)
        v[:, torch.as_tensor(self.free)] = lo + (hi - lo) * u
        return v

    def to_theta(self, u: np.ndarray | torch.Tensor) -> CaptureParams:
        return CaptureParams.from_vector(self.to_vector(u), channels=self.channels, effects=self.effects,
                                         validate=False)

    def from_theta(self, theta: CaptureParams) -> np.ndarray:
        """Θ -> (N, D) search coordinates (periodic values folded)."""
        v = theta.to_vector().double().numpy()[:, self.free]
        lo, hi = self.low[self.free], self.high[self.free]
        u = (v - lo) / np.where(hi > lo, hi - lo, 1.0)
        per = self.periodic[self.free]
        u[:, per] = np.mod(u[:, per], 1.0)
        u = np.where(per, u, np.clip(u, 0.0, 1.0))
        if self.scale_range is not None:  # the scale is not in Θ: start it mid-range
            u = np.concatenate([u, np.full((len(u), 1), 0.5)], axis=1)
        return u

    def pose_to_u(self, poses: np.ndarray, base: np.ndarray) -> np.ndarray:
        """Search coordinates with (α, β, γ) from ``poses`` (N, 3) and the rest from ``base`` (D,).

        Raises:
            ValueError: a rotation angle is not free in this space.
        """
        names = self.free_names()
        missing = [k for k in ("alpha", "beta", "gamma") if k not in names]
        if missing:
            raise ValueError(f"the rotation {missing} is not free in this search space")
        u = np.repeat(np.asarray(base, float)[None], len(poses), axis=0)
        for j, k in enumerate(("alpha", "beta", "gamma")):
            col = self.names.index(k)
            lo, hi = self.low[col], self.high[col]
            v = (np.asarray(poses, float)[:, j] - lo) / (hi - lo)
            u[:, names.index(k)] = np.mod(v, 1.0) if self.periodic[col] else np.clip(v, 0.0, 1.0)
        return u

    def free_names(self) -> list[str]:
        return [n for n, f in zip(self.names, self.free) if f] + (["object_scale"] if self.scale_range else [])


def rotation_grid(n: int) -> tuple[np.ndarray, float]:
    """About ``n`` rotations spread near-uniformly over SO(3), as (α, β, γ) (M, 3), and their spacing (rad).

    View directions on a Fibonacci sphere (which side of the object faces the
    camera: α, β) times equally spaced in-plane angles γ; the Haar measure is
    uniform direction × uniform γ, and the two counts share one spacing s
    (``4π/s²`` directions, ``2π/s`` angles, ``8π²/s³`` rotations in all).
    Deterministic.

    Example:
        >>> g, s = rotation_grid(240)
        >>> g.shape[1], 150 <= len(g) <= 300, round(float(np.degrees(s)))
        (3, True, 40)
    """
    if n < 8:
        raise ValueError(f"a rotation grid needs n >= 8 rotations, got {n}")
    s = (8 * math.pi ** 2 / n) ** (1 / 3)
    n_gamma = max(4, int(round(2 * math.pi / s)))
    n_dir = max(2, int(round(n / n_gamma)))
    i = np.arange(n_dir)
    z = 1 - (2 * i + 1) / n_dir
    r = np.sqrt(np.clip(1 - z ** 2, 0, 1))
    phi = i * math.pi * (3 - math.sqrt(5))
    dx, dy, dz = r * np.cos(phi), r * np.sin(phi), z
    # the camera's axis in the object frame for R = Rz(γ) Ry(β) Rx(α) is (-sin β, sin α cos β, cos α cos β)
    beta = -np.arcsin(np.clip(dx, -1, 1))
    alpha = np.arctan2(dy, dz)
    gamma = -math.pi + 2 * math.pi * np.arange(n_gamma) / n_gamma
    grid = np.stack([np.repeat(alpha, n_gamma), np.repeat(beta, n_gamma), np.tile(gamma, n_dir)], axis=1)
    return grid, s


def rotation_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Geodesic angle (rad) between rotation matrices (..., 3, 3)."""
    tr = np.einsum("...ij,...ij->...", a, b)  # trace(aᵀ b)
    return np.arccos(np.clip((tr - 1) / 2, -1.0, 1.0))


class RenderObjective:
    """``f(u) = d(X, S(Θ(u), B))`` for a population of candidates at once.

    Args:
        target: (1, C, P, P) real seed patch X_i in [0, 1].
        background: (1, C, P, P) its background B_i.
        cache: :class:`~synthaug.render.cache.ViewCache` of the mesh.
        distance: a distance module ``d(x_real, x_syn) -> (N,)``.
        space: the search space.
        object_scale: mesh unit length as a fraction of the patch side.
        noise_seed: seed of the fixed object-noise field.
        origin: (1, 2) pixel (x, y) of the patch's top-left corner in its full
            frame, and frame_size (1, 2) the frame's (W, H): for position-aware
            effects (vignetting, lens distortion...).
        extras: extra (1, ...) layers passed to the effects.
        chunk: candidates rendered per torch pass (about 100 is fastest here: larger
            batches fall out of cache).
    """

    def __init__(self, target: torch.Tensor, background: torch.Tensor, cache: Any, distance: Any, space: FitSpace,
                 *, object_scale: float = 0.7, noise_seed: int = 0, chunk: int = 96,
                 origin: torch.Tensor | None = None, frame_size: torch.Tensor | None = None,
                 extras: dict[str, torch.Tensor] | None = None) -> None:
        if target.ndim != 4 or target.shape[0] != 1:
            raise ValueError(f"target must be (1, C, P, P), got {tuple(target.shape)}")
        if background.shape != target.shape:
            raise ValueError(f"background {tuple(background.shape)} must match target {tuple(target.shape)}")
        if target.shape[1] != space.channels:
            raise ValueError(f"target has {target.shape[1]} channels, the search space {space.channels}")
        self.target = target.float()
        self.background = background.float()
        self.cache = cache
        self.distance = distance
        self.space = space
        self.object_scale = float(object_scale)
        self.chunk = int(chunk)
        shape = tuple(target.shape)
        self.fields = sample_fields(space.effects, shape, torch.Generator().manual_seed(int(noise_seed)))
        self.origin = None if origin is None else torch.as_tensor(origin, dtype=torch.float32).reshape(1, 2)
        self.frame_size = None if frame_size is None else torch.as_tensor(frame_size, dtype=torch.float32).reshape(1, 2)
        self.extras = dict(extras or {})
        self.n_evals = 0
        self._target_features: torch.Tensor | None = None

    def target_features(self) -> torch.Tensor:
        """The distance's features of the target (computed once; the distance must define ``features``)."""
        if self._target_features is None:
            self._target_features = self.distance.features(self.target)
        return self._target_features

    def render(self, u: np.ndarray | torch.Tensor) -> torch.Tensor:
        """S(Θ(u), B) for (N, D) coordinates -> (N, C, P, P)."""
        return _render_parts([(self, u)])

    @torch.no_grad()
    def __call__(self, u: np.ndarray | torch.Tensor) -> np.ndarray:
        u = np.atleast_2d(np.asarray(u, dtype=np.float64))
        out = np.empty(len(u))
        for i in range(0, len(u), self.chunk):
            images = self.render(u[i:i + self.chunk])
            out[i:i + self.chunk] = self.distance(self.target, images).double().numpy()
        self.n_evals += len(u)
        if not np.all(np.isfinite(out)):
            out = np.where(np.isfinite(out), out, math.inf)
        return out


def _render_parts(parts: Sequence[tuple[RenderObjective, Any]]) -> torch.Tensor:
    """S(Θ(u), B) of several objectives' candidates in one pass, rows in order: ``[(objective, u), ...]`` ->
    ``(Σ N, C, P, P)``. The objectives share the view cache, effects and patch size (see :func:`score_together`);
    each row is rendered with its own objective's background, scale, noise fields and frame geometry."""
    first = parts[0][0]
    theta = CaptureParams.from_vector(torch.cat([o.space.to_vector(u) for o, u in parts]), channels=first.space.channels,
                                      effects=first.space.effects, validate=False).to(torch.float32)
    scale = torch.cat([o.space.scale(u, o.object_scale).float() for o, u in parts])
    cov, nrm = first.cache.layers(theta.alpha, theta.beta, theta.gamma, theta.t_x, theta.t_y,
                                  size=first.target.shape[-1], object_scale=scale)
    n = [len(np.atleast_2d(u)) for _, u in parts]
    cat = lambda get: torch.cat([get(o).expand(k, *get(o).shape[1:]) for (o, _), k in zip(parts, n)])  # noqa: E731
    return simulate(cov, nrm, cat(lambda o: o.background), theta,
                    fields={k: cat(lambda o, k=k: o.fields[k]) for k in first.fields},
                    origin=None if first.origin is None else cat(lambda o: o.origin),
                    frame_size=None if first.frame_size is None else cat(lambda o: o.frame_size),
                    extras={k: cat(lambda o, k=k: o.extras[k]) for k in first.extras})


@torch.no_grad()
def score_together(objectives: Sequence[RenderObjective], us: Sequence[np.ndarray]) -> list[np.ndarray]:
    """Several seeds' candidates scored in one batched pass: ``[objectives[k](us[k]) for k]``, with the same values.

    Each seed's population is small (CMA-ES asks for about a dozen candidates at a time) and a call of the
    objective has a fixed cost that such a batch does not amortise (issue 19: 0.31 ms per evaluation at batch
    12 against 0.16 at 96). Fitting several seeds in lockstep and scoring their populations together pays that
    cost once. Every value is computed per candidate (render, effects and features act on each image alone), so
    a seed's values do not depend on the company it is scored in; the tests compare against separate calls.

    Args:
        objectives: the seeds' objectives; they must share the view cache, the distance and the patch size.
        us: each objective's ``(N_k, D_k)`` search coordinates (an empty population is allowed).

    Returns:
        One ``(N_k,)`` array of distances per objective (``inf`` where a value is not finite).
    """
    from synthaug.distances.registry import Distance

    if len(objectives) != len(us):
        raise ValueError(f"{len(objectives)} objectives but {len(us)} populations")
    if not objectives:
        return []
    first = objectives[0]
    for o in objectives[1:]:
        if o.cache is not first.cache or o.distance is not first.distance:
            raise ValueError("objectives scored together must share one view cache and one distance")
        if o.target.shape[1:] != first.target.shape[1:]:
            raise ValueError(f"objectives scored together must share a patch shape: {tuple(o.target.shape[1:])} "
                             f"vs {tuple(first.target.shape[1:])}")
        if o.space.effects != first.space.effects or o.space.channels != first.space.channels:
            raise ValueError("objectives scored together must search the same effects and channels")
        if (o.origin is None) != (first.origin is None) or set(o.extras) != set(first.extras) \
                or set(o.fields) != set(first.fields):
            raise ValueError("objectives scored together must have the same frame geometry keys and effect fields")
    us = [np.atleast_2d(np.asarray(u, dtype=np.float64)) for u in us]
    counts = [len(u) for u in us]
    owner = np.repeat(np.arange(len(us)), counts)
    row = np.concatenate([np.arange(c) for c in counts]) if sum(counts) else np.zeros(0, int)
    out = [np.empty(c) for c in counts]
    dist = first.distance
    by_features = type(dist).forward is Distance.forward
    f_real = torch.cat([o.target_features() for o in objectives]) if by_features else None
    chunk = first.chunk
    for i in range(0, len(owner), chunk):
        sel = owner[i:i + chunk]
        groups = [(k, row[i:i + chunk][sel == k]) for k in np.unique(sel)]
        parts = [(objectives[k], us[k][r]) for k, r in groups]
        images = _render_parts(parts)
        n_rows = torch.as_tensor([len(u) for _, u in parts])
        if by_features:
            keep = torch.as_tensor([k for k, _ in groups])
            d = dist.compare(f_real[keep].repeat_interleave(n_rows, 0), dist.features(images))
        else:
            d = dist(torch.cat([o.target.expand(len(u), *o.target.shape[1:]) for o, u in parts]), images)
        d = d.double().numpy()
        start = 0
        for (k, r), n in zip(groups, n_rows.tolist()):
            out[k][r] = d[start:start + n]
            start += n
    for o, c in zip(objectives, counts):
        o.n_evals += c
    return [np.where(np.isfinite(v), v, math.inf) for v in out]
