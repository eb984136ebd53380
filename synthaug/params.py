"""The parameter vector Θ of the paper: pose plus capture parameters.

Θ = [α, β, γ, t_x, t_y | σ_s, σ_u, σ_v, α_m, σ_n, w_d] (Rozantsev et al., eq. 1).
The first five ("extrinsic") place the object; the rest ("intrinsic", here
*capture* parameters) belong to the capture effects in :mod:`synthaug.effects`.
The capture parameters are declared effect by effect (:data:`EFFECT_PARAM_SPECS`);
an effect registered later declares its own :class:`ParamSpec` s and extends Θ
without touching this module.

Pose parameters are one value per sample, shape ``(B,)``; capture parameters
are one value per sample *and channel*, shape ``(B, C)`` (``C = 1`` grayscale,
``C = 3`` for the paper's RGB extension, which fits each channel on its own).

Example:
    >>> import torch
    >>> theta = CaptureParams.default(batch_size=2)
    >>> theta.sigma_s.shape, theta.alpha.shape
    (torch.Size([2, 1]), torch.Size([2]))
    >>> v = theta.to_vector()
    >>> v.shape
    torch.Size([2, 11])
    >>> CaptureParams.from_vector(v).sigma_s.shape
    torch.Size([2, 1])
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Iterable, Mapping, Sequence

import torch

from synthaug._io import atomic_write_text  # noqa: F401  (re-exported: used by other modules)
from synthaug._io import check_header, read_versioned_json

FORMAT_NAME = "synthaug.capture_params"
FORMAT_VERSION = 1
# A fit result is a capture-parameter file whose metadata says so (written by
# ``synthaug fit``); its version is checked here, where the file is read.
FIT_RESULT_FORMAT = "synthaug.fit"
FIT_RESULT_VERSION = 1


@dataclass(frozen=True)
class ParamSpec:
    """One scalar parameter of Θ.

    Args:
        name: attribute name (``sigma_s``).
        symbol: the paper's symbol (``σ_s``), for docs and plots.
        unit: unit of the value (``px``, ``rad``, ``intensity``...).
        low: smallest valid value.
        high: largest valid value.
        default: value of an "effect off"-like neutral default.
        doc: one line of meaning.
        per_channel: ``True`` for capture parameters (shape ``(B, C)``),
            ``False`` for pose (shape ``(B,)``).
        sample_low: lower bound of the default sampling range (``low`` if None).
        sample_high: upper bound of the default sampling range (``high`` if None).
        periodic: the value is an angle that wraps (validation then accepts any
            finite value and :meth:`CaptureParams.wrapped` folds it into range).
    """

    name: str
    symbol: str
    unit: str
    low: float
    high: float
    default: float
    doc: str
    per_channel: bool = True
    sample_low: float | None = None
    sample_high: float | None = None
    periodic: bool = False

    @property
    def sampling_range(self) -> tuple[float, float]:
        lo = self.low if self.sample_low is None else self.sample_low
        hi = self.high if self.sample_high is None else self.sample_high
        return lo, hi


POSE_SPECS: tuple[ParamSpec, ...] = (
    ParamSpec("alpha", "α", "rad", -math.pi, math.pi, 0.0,
              "out-of-plane rotation about the object's x axis", per_channel=False, periodic=True),
    ParamSpec("beta", "β", "rad", -math.pi / 2, math.pi / 2, 0.0,
              "out-of-plane rotation about the object's y axis (elevation)", per_channel=False),
    ParamSpec("gamma", "γ", "rad", -math.pi, math.pi, 0.0,
              "in-plane rotation about the optical axis", per_channel=False, periodic=True),
    ParamSpec("t_x", "t_x", "patch", -0.5, 0.5, 0.0,
              "horizontal offset of the object centre, fraction of the patch side",
              per_channel=False, sample_low=-0.1, sample_high=0.1),
    ParamSpec("t_y", "t_y", "patch", -0.5, 0.5, 0.0,
              "vertical offset of the object centre (down positive), fraction of the patch side",
              per_channel=False, sample_low=-0.1, sample_high=0.1),
)
POSE_NAMES: tuple[str, ...] = tuple(s.name for s in POSE_SPECS)


# ---------------------------------------------------------- capture parameters, effect by effect
# Θ's capture parameters are declared here, next to the pose: Θ is this module's concept, and the
# effects (synthaug.effects) are functions of it. Each built-in effect's class reads its tuple from
# EFFECT_PARAM_SPECS; an effect registered later (synthaug.effects.register_effect) declares its
# own parameters through declare_effect_params, and nothing here changes.

# The paper's four effects, in the paper's order of presentation.
PAPER_EFFECTS: tuple[str, ...] = ("boundary_blur", "motion_blur", "object_noise", "material")

# σ ranges (px) are those of a 40-64 px patch; the effects' blur padding follows them.
SIGMA_S_MAX = 3.0
SIGMA_M_MAX = 5.0
SIGMA_N_MAX = 0.3
DEFOCUS_SIGMA_MAX = 3.0
SHARPEN_SIGMA_MAX = 3.0
TEXTURE_SCALE_MIN = 0.3
TEXTURE_SCALE_MAX = 4.0

_DECLARED: dict[str, tuple[ParamSpec, ...]] = {
    # paper: the paper's four (Rozantsev et al. 2015, Sec. 3)
    "material": (
        ParamSpec("w_d", "w_d", "reflectance", 0.0, 1.0, 0.5,
                  "diffuse reflection weight: object intensity under the default light",
                  sample_low=0.05, sample_high=0.9),
    ),
    "motion_blur": (
        ParamSpec("sigma_u", "σ_u", "px", 0.0, SIGMA_M_MAX, 0.0, "motion-blur std along α_m",
                  sample_high=2.0),
        ParamSpec("sigma_v", "σ_v", "px", 0.0, SIGMA_M_MAX, 0.0, "motion-blur std across α_m",
                  sample_high=2.0),
        ParamSpec("alpha_m", "α_m", "rad", -math.pi / 2, math.pi / 2, 0.0,
                  "motion direction from +x toward +y (π-periodic)", periodic=True),
    ),
    "boundary_blur": (
        ParamSpec("sigma_s", "σ_s", "px", 0.0, SIGMA_S_MAX, 0.0, "boundary-blur std", sample_high=1.5),
    ),
    "object_noise": (
        ParamSpec("sigma_n", "σ_n", "intensity", 0.0, SIGMA_N_MAX, 0.0,
                  "std of the noise added to object pixels (image in [0, 1])", sample_high=0.08),
    ),
    # material: material extensions (issue 6)
    "object_texture": (
        ParamSpec("texture_amp", "a", "relative", 0.0, 1.0, 0.0,
                  "relative std of the albedo variation (0 = none)", sample_high=0.6),
        ParamSpec("texture_scale", "ℓ", "px", TEXTURE_SCALE_MIN, TEXTURE_SCALE_MAX, 1.0,
                  "std of the Gaussian that smooths the albedo field (its correlation length)",
                  sample_low=0.5, sample_high=2.5),
    ),
    # camera: the camera candidates of the diagnosis
    "specular": (
        ParamSpec("specular_ks", "k_s", "reflectance", 0.0, 1.0, 0.0, "specular reflection weight",
                  sample_high=0.6),
        ParamSpec("specular_shininess", "p_s", "exponent", 2.0, 200.0, 30.0,
                  "Blinn-Phong exponent: larger = smaller, sharper highlights", sample_low=5.0, sample_high=80.0),
    ),
    "haze": (
        ParamSpec("haze_amount", "h", "fraction", 0.0, 0.95, 0.0, "1 - transmission between object and camera",
                  sample_high=0.5),
        ParamSpec("haze_airlight", "A", "intensity", 0.0, 1.0, 0.8, "airlight (horizon sky) intensity",
                  sample_low=0.5),
    ),
    "vignetting": (
        ParamSpec("vignette_k", "k_v", "fraction", 0.0, 0.9, 0.0, "fraction of light lost at the frame corners",
                  sample_high=0.5),
    ),
    "exposure": (
        ParamSpec("exposure_gain", "g_e", "factor", 0.25, 4.0, 1.0, "exposure gain", sample_low=0.7,
                  sample_high=1.4),
        ParamSpec("exposure_offset", "o_e", "intensity", -0.3, 0.3, 0.0, "black-level offset",
                  sample_low=-0.05, sample_high=0.05),
    ),
    "white_balance": (
        ParamSpec("wb_gain", "g_c", "factor", 0.5, 2.0, 1.0, "white-balance gain of the channel",
                  sample_low=0.8, sample_high=1.25),
    ),
    "rotor_blur": (
        ParamSpec("rotor_opacity", "ρ", "fraction", 0.0, 1.0, 1.0,
                  "fraction of the exposure a rotor-disc pixel is covered by a blade (1 = solid disc)",
                  sample_low=0.1),
    ),
    "rolling_shutter": (
        ParamSpec("rs_skew", "s_x", "px/row", -0.5, 0.5, 0.0, "horizontal object displacement per image row",
                  sample_low=-0.15, sample_high=0.15),
        ParamSpec("rs_stretch", "s_y", "px/row", -0.3, 0.3, 0.0, "vertical object displacement per image row",
                  sample_low=-0.08, sample_high=0.08),
    ),
    "defocus": (
        ParamSpec("defocus_sigma", "σ_f", "px", 0.0, DEFOCUS_SIGMA_MAX, 0.0, "defocus PSF std", sample_high=1.5),
    ),
    "chromatic_aberration": (
        ParamSpec("ca_shift", "δ_ca", "px", 0.0, 4.0, 0.0, "red/blue displacement at the frame corners (frame px)",
                  sample_high=2.5),
    ),
    "lens_distortion": (
        ParamSpec("distortion_k1", "k₁", "1", -0.3, 0.3, 0.0, "radial distortion coefficient (r = 1 at corners)",
                  sample_low=-0.2, sample_high=0.1),
    ),
    "shot_noise": (
        ParamSpec("shot_sigma", "σ_shot", "intensity", 0.0, 0.2, 0.0, "noise std at full intensity (var ∝ I)",
                  sample_high=0.08),
    ),
    "gamma": (
        ParamSpec("gamma_g", "g", "exponent", 0.4, 2.5, 1.0, "tone-curve exponent (1 = linear)",
                  sample_low=0.7, sample_high=1.4),
    ),
    "sharpening": (
        ParamSpec("sharpen_amount", "a_s", "factor", 0.0, 3.0, 0.0, "unsharp-mask amount", sample_high=1.5),
        ParamSpec("sharpen_sigma", "σ_us", "px", 0.3, SHARPEN_SIGMA_MAX, 1.0, "unsharp-mask radius (Gaussian std)",
                  sample_low=0.5, sample_high=2.0),
    ),
    "compression": (
        ParamSpec("jpeg_quality", "q", "JPEG quality", 5.0, 100.0, 100.0, "JPEG quality (100 = off)",
                  sample_low=30.0, sample_high=95.0),
    ),
}
EFFECT_PARAM_SPECS: Mapping[str, tuple[ParamSpec, ...]] = MappingProxyType(_DECLARED)
"""Effect name -> its capture parameters (read-only view; add with :func:`declare_effect_params`)."""


def declare_effect_params(effect: str, specs: Sequence[ParamSpec]) -> None:
    """Declare the capture parameters of ``effect`` (done by ``register_effect``; once per name).

    Raises ``ValueError`` if ``effect`` is already declared with other parameters.
    """
    specs = tuple(specs)
    if not all(isinstance(s, ParamSpec) for s in specs):
        raise ValueError(f"parameters of effect {effect!r} must be ParamSpec instances, got {specs!r}")
    if effect in _DECLARED and _DECLARED[effect] != specs:
        raise ValueError(f"effect {effect!r} is already declared with parameters "
                         f"{[s.name for s in _DECLARED[effect]]}")
    _DECLARED[effect] = specs


def effect_param_specs(effects: Sequence[str] | None) -> tuple[ParamSpec, ...]:
    """The capture parameters of ``effects`` (None: the paper's four), in Θ's order.

    Raises ``ValueError`` for an unknown effect or a parameter name two effects share.
    """
    names = PAPER_EFFECTS if effects is None else tuple(effects)
    specs: list[ParamSpec] = []
    seen: set[str] = set(POSE_NAMES)
    for name in names:
        for spec in _declared(name):
            if spec.name in seen:
                raise ValueError(f"parameter {spec.name!r} of effect {name!r} is already defined")
            seen.add(spec.name)
            specs.append(spec)
    return tuple(specs)


def _declared(effect: str) -> tuple[ParamSpec, ...]:
    try:
        return _DECLARED[effect]
    except KeyError:
        raise ValueError(f"unknown effect {effect!r}; registered: {sorted(_DECLARED)}") from None


class CaptureParams:
    """A batch of Θ vectors: pose (α, β, γ, t_x, t_y) and capture parameters.

    The field set is the pose plus the parameters of ``effects`` (default: the
    paper's four effects, giving σ_s, σ_u, σ_v, α_m, σ_n, w_d). Fields are read
    as attributes (``theta.sigma_n``). Values are validated at construction:
    NaN/inf, negative σ and out-of-range values raise ``ValueError`` naming the
    field and the value.

    Args:
        values: mapping name -> tensor-like. Pose fields broadcast to ``(B,)``,
            capture fields to ``(B, C)``. Missing fields take their spec's default.
        channels: C, number of image channels (1 grayscale, 3 RGB).
        effects: names of the effects whose parameters Θ holds.
        validate: check ranges (turn off only for values you produced yourself,
            e.g. clamped optimiser candidates).
    """

    def __init__(
        self,
        values: Mapping[str, Any] | None = None,
        *,
        channels: int = 1,
        effects: Sequence[str] | None = None,
        validate: bool = True,
    ) -> None:
        if channels not in (1, 3):
            raise ValueError(f"channels must be 1 or 3, got {channels}")
        values = dict(values or {})
        self.effects: tuple[str, ...] = resolve_effect_names(effects)
        self.specs: tuple[ParamSpec, ...] = POSE_SPECS + effect_param_specs(self.effects)
        self.channels = channels
        known = {s.name for s in self.specs}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"unknown parameter(s) {unknown}; known: {sorted(known)}")
        batch = 1
        tensors: dict[str, torch.Tensor] = {}
        for spec in self.specs:
            if spec.name in values:
                t = torch.as_tensor(values[spec.name], dtype=_float_dtype(values[spec.name]))
                tensors[spec.name] = t
                if t.ndim >= 1:
                    batch = max(batch, t.shape[0])
        self._values: dict[str, torch.Tensor] = {}
        for spec in self.specs:
            t = tensors.get(spec.name)
            if t is None:
                t = torch.tensor(spec.default, dtype=torch.float32)
            self._values[spec.name] = _broadcast(spec, t, batch, channels)
        if validate:
            self.validate()

    # ------------------------------------------------------------------ access
    def __getattr__(self, name: str) -> torch.Tensor:
        values = self.__dict__.get("_values")
        if values is not None and name in values:
            return values[name]
        raise AttributeError(f"{type(self).__name__} has no field {name!r}")

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.specs)

    @property
    def batch_size(self) -> int:
        return int(self._values["alpha"].shape[0])

    def __len__(self) -> int:
        return self.batch_size

    def as_dict(self) -> dict[str, torch.Tensor]:
        return dict(self._values)

    def pose(self) -> dict[str, torch.Tensor]:
        return {n: self._values[n] for n in POSE_NAMES}

    def effect_params(self, effect: str) -> dict[str, torch.Tensor]:
        return {s.name: self._values[s.name] for s in _declared(effect)}

    def __getitem__(self, index: int | slice | Sequence[int] | torch.Tensor) -> "CaptureParams":
        if isinstance(index, int):
            index = [index]
        return self._new({k: v[index] for k, v in self._values.items()})

    def replace(self, **values: Any) -> "CaptureParams":
        """A copy with some fields replaced (validated)."""
        new = dict(self._values)
        new.update(values)
        return CaptureParams(new, channels=self.channels, effects=self.effects)

    def to(self, *args: Any, **kwargs: Any) -> "CaptureParams":
        return self._new({k: v.to(*args, **kwargs) for k, v in self._values.items()})

    def _new(self, values: dict[str, torch.Tensor]) -> "CaptureParams":
        obj = object.__new__(CaptureParams)
        obj.effects, obj.specs, obj.channels = self.effects, self.specs, self.channels
        obj._values = values
        return obj

    @staticmethod
    def cat(items: Sequence["CaptureParams"]) -> "CaptureParams":
        if not items:
            raise ValueError("cannot concatenate an empty list of CaptureParams")
        first = items[0]
        for it in items[1:]:
            if it.names != first.names or it.channels != first.channels:
                raise ValueError("CaptureParams to concatenate must have the same fields and channels")
        return first._new({n: torch.cat([it._values[n] for it in items]) for n in first.names})

    # --------------------------------------------------------------- validate
    def validate(self) -> None:
        for spec in self.specs:
            v = self._values[spec.name]
            bad = ~torch.isfinite(v)
            if bad.any():
                raise ValueError(f"{spec.name} ({spec.symbol}) must be finite, got {v[bad][0].item()}")
            if spec.periodic:
                continue
            if spec.name.startswith("sigma") and (v < 0).any():
                raise ValueError(f"{spec.name} ({spec.symbol}) must be >= 0, got {v[v < 0][0].item()}")
            out = (v < spec.low - 1e-6) | (v > spec.high + 1e-6)
            if out.any():
                raise ValueError(
                    f"{spec.name} ({spec.symbol}) must be in [{spec.low}, {spec.high}] {spec.unit}, "
                    f"got {v[out][0].item()}"
                )

    def wrapped(self) -> "CaptureParams":
        """Periodic angles folded into their canonical range (no validation)."""
        out = {}
        for spec in self.specs:
            v = self._values[spec.name]
            if spec.periodic:
                period = spec.high - spec.low
                v = torch.remainder(v - spec.low, period) + spec.low
            out[spec.name] = v
        return self._new(out)

    # ------------------------------------------------------------ flat vector
    def to_vector(self) -> torch.Tensor:
        """Flat ``(B, P)`` tensor, P = 5 + C * (number of capture params), spec order."""
        cols = []
        for spec in self.specs:
            v = self._values[spec.name]
            cols.append(v.reshape(v.shape[0], -1))
        return torch.cat(cols, dim=1)

    @classmethod
    def vector_names(cls, *, channels: int = 1, effects: Sequence[str] | None = None) -> list[str]:
        """Column names of :meth:`to_vector` (``sigma_s[0]`` for channel 0...)."""
        names = list(POSE_NAMES)
        for spec in effect_param_specs(resolve_effect_names(effects)):
            names += [f"{spec.name}[{c}]" for c in range(channels)] if channels > 1 else [spec.name]
        return names

    @classmethod
    def bounds(cls, *, channels: int = 1, effects: Sequence[str] | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """Lower and upper bound of every column of :meth:`to_vector`."""
        lo, hi = [], []
        for spec in POSE_SPECS + effect_param_specs(resolve_effect_names(effects)):
            k = channels if spec.per_channel else 1
            lo += [spec.low] * k
            hi += [spec.high] * k
        return torch.tensor(lo), torch.tensor(hi)

    @classmethod
    def from_vector(
        cls,
        vector: torch.Tensor,
        *,
        channels: int = 1,
        effects: Sequence[str] | None = None,
        validate: bool = True,
    ) -> "CaptureParams":
        """Inverse of :meth:`to_vector`. Keeps the autograd graph of ``vector``."""
        vector = torch.as_tensor(vector)
        if vector.ndim == 1:
            vector = vector[None]
        eff = resolve_effect_names(effects)
        specs = POSE_SPECS + effect_param_specs(eff)
        width = sum(channels if s.per_channel else 1 for s in specs)
        if vector.ndim != 2 or vector.shape[1] != width:
            raise ValueError(f"expected a (B, {width}) vector for channels={channels}, got {tuple(vector.shape)}")
        values, i = {}, 0
        for spec in specs:
            k = channels if spec.per_channel else 1
            col = vector[:, i:i + k]
            values[spec.name] = col if spec.per_channel else col[:, 0]
            i += k
        return cls(values, channels=channels, effects=eff, validate=validate)

    # ---------------------------------------------------------------- sampling
    @classmethod
    def sample(
        cls,
        batch_size: int,
        *,
        generator: torch.Generator,
        channels: int = 1,
        effects: Sequence[str] | None = None,
        ranges: Mapping[str, tuple[float, float]] | None = None,
    ) -> "CaptureParams":
        """Draw Θ uniformly in each field's sampling range (``ranges`` overrides)."""
        eff = resolve_effect_names(effects)
        ranges = dict(ranges or {})
        specs = POSE_SPECS + effect_param_specs(eff)
        unknown = sorted(set(ranges) - {s.name for s in specs})
        if unknown:
            raise ValueError(f"unknown parameter(s) in ranges: {unknown}")
        values = {}
        for spec in specs:
            lo, hi = ranges.get(spec.name, spec.sampling_range)
            if not (math.isfinite(lo) and math.isfinite(hi)) or hi < lo:
                raise ValueError(f"range for {spec.name} must be finite with low <= high, got ({lo}, {hi})")
            shape = (batch_size, channels) if spec.per_channel else (batch_size,)
            values[spec.name] = lo + (hi - lo) * torch.rand(shape, generator=generator)
        return cls(values, channels=channels, effects=eff)

    @classmethod
    def default(cls, batch_size: int = 1, *, channels: int = 1, effects: Sequence[str] | None = None) -> "CaptureParams":
        eff = resolve_effect_names(effects)
        values = {s.name: torch.full((batch_size,), s.default) for s in POSE_SPECS}
        return cls(values, channels=channels, effects=eff)

    # -------------------------------------------------------------------- I/O
    def to_records(self) -> list[dict[str, Any]]:
        rows = []
        for b in range(self.batch_size):
            row: dict[str, Any] = {}
            for spec in self.specs:
                v = self._values[spec.name][b]
                row[spec.name] = v.tolist() if spec.per_channel else float(v)
            rows.append(row)
        return rows

    def save(self, path: str | os.PathLike, *, extra: Sequence[Mapping[str, Any]] | None = None,
             metadata: Mapping[str, Any] | None = None) -> None:
        """Write a human-readable, versioned JSON file (atomically).

        Args:
            path: output file.
            extra: optional per-row dicts stored next to each Θ (e.g. fit distance).
            metadata: optional free-form header fields.
        """
        if extra is not None and len(extra) != self.batch_size:
            raise ValueError(f"extra must have {self.batch_size} rows, got {len(extra)}")
        doc = {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "channels": self.channels,
            "effects": list(self.effects),
            "fields": [
                {"name": s.name, "symbol": s.symbol, "unit": s.unit, "low": s.low, "high": s.high,
                 "per_channel": s.per_channel, "doc": s.doc}
                for s in self.specs
            ],
            "metadata": dict(metadata or {}),
            "rows": [
                {"theta": row, **({"extra": dict(extra[i])} if extra is not None else {})}
                for i, row in enumerate(self.to_records())
            ],
        }
        atomic_write_text(path, json.dumps(doc, indent=1))

    @classmethod
    def load(cls, path: str | os.PathLike) -> "CaptureParams":
        """Read a file written by :meth:`save`."""
        return cls.load_with_extra(path)[0]

    @classmethod
    def load_with_extra(cls, path: str | os.PathLike) -> tuple["CaptureParams", list[dict[str, Any]], dict[str, Any]]:
        path = Path(path)
        doc = read_versioned_json(path, format=FORMAT_NAME, version=FORMAT_VERSION, what="capture-parameter file")
        meta = doc.get("metadata", {})
        if isinstance(meta, dict) and meta.get("result_format") == FIT_RESULT_FORMAT:
            check_header(meta, format=FIT_RESULT_FORMAT, version=FIT_RESULT_VERSION, what="fit result",
                         source=path, format_key="result_format", version_key="result_version")
        rows = doc.get("rows") or []
        if not rows:
            raise ValueError(f"{path}: the file holds no rows")
        try:
            channels = int(doc.get("channels", 1))
            effects = doc.get("effects")
            names = [f["name"] for f in doc["fields"]]
            values = {n: [r["theta"][n] for r in rows] for n in names}
            params = cls(values, channels=channels, effects=effects)
            extra = [r.get("extra", {}) for r in rows]
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"{path}: malformed capture-parameter file ({type(e).__name__}: {e})") from None
        return params, extra, meta if isinstance(meta, dict) else {}

    def __repr__(self) -> str:
        return f"CaptureParams(batch_size={self.batch_size}, channels={self.channels}, effects={list(self.effects)})"


def resolve_effect_names(effects: Iterable[str] | None) -> tuple[str, ...]:
    """``effects`` as a tuple of registered effect names (None: the paper's four); unknown names raise."""
    names = PAPER_EFFECTS if effects is None else tuple(effects)
    for n in names:
        _declared(n)  # a clear ValueError for an unknown name
    return tuple(names)


def _float_dtype(x: Any) -> torch.dtype:
    if isinstance(x, torch.Tensor) and x.is_floating_point():
        return x.dtype
    return torch.float32


def _broadcast(spec: ParamSpec, t: torch.Tensor, batch: int, channels: int) -> torch.Tensor:
    if spec.per_channel:
        if t.ndim == 0:
            return t.expand(batch, channels).clone()
        if t.ndim == 1:
            if t.shape[0] == batch:
                return t[:, None].expand(batch, channels).clone()
            if t.shape[0] == channels:
                return t[None].expand(batch, channels).clone()
        if t.ndim == 2 and t.shape[0] in (1, batch) and t.shape[1] in (1, channels):
            return t.expand(batch, channels).clone() if t.shape != (batch, channels) else t
        raise ValueError(f"{spec.name}: expected shape (B,), (B, {channels}) or scalar, got {tuple(t.shape)}")
    if t.ndim == 0:
        return t.expand(batch).clone()
    if t.ndim == 1 and t.shape[0] in (1, batch):
        return t.expand(batch).clone() if t.shape[0] != batch else t
    raise ValueError(f"{spec.name}: expected shape (B,) or scalar, got {tuple(t.shape)}")


def fitted_object_scales(extra: Sequence[Mapping[str, Any]]) -> torch.Tensor | None:
    """Per-seed object scales stored by ``synthaug fit`` in a file's ``extra`` rows, or None.

    Example:
        >>> fitted_object_scales([{"object_scale": 0.3}, {"object_scale": 0.5}]).tolist()
        [0.30000001192092896, 0.5]
        >>> fitted_object_scales([{"distance": 1.0}]) is None
        True
    """
    if not extra or not all("object_scale" in e for e in extra):
        return None
    return torch.tensor([float(e["object_scale"]) for e in extra], dtype=torch.float32)
