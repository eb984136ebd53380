"""The truth of a reference-camera seed set: the hidden settings in the model's units, ``truth.json``
(a :class:`~synthaug.params.CaptureParams` file of the true Θ per seed) and :func:`load_truth`.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

from synthaug.effects.camera import CAMERA_EFFECTS
from synthaug.effects.registry import PAPER_EFFECTS, get_effect
from synthaug.params import CaptureParams


_FORMAT = "synthaug.reference_camera"
_VERSION = 1


def _model_units(cam: dict[str, dict[str, float]], frame_scale: float) -> dict[str, dict[str, float]]:
    """The hidden settings as the model's parameters of a patch (σ in patch px)."""
    out: dict[str, dict[str, float]] = {}
    for eff, params in cam.items():
        if eff not in CAMERA_EFFECTS:
            continue
        p = {s.name: params[s.name] for s in get_effect(eff).params if s.name in params}
        if eff == "defocus":
            p["defocus_sigma"] = params["defocus_sigma"] / frame_scale
        if eff == "sharpening":
            p["sharpen_sigma"] = params["sharpen_sigma"] / frame_scale
        out[eff] = p
    return out


def _truth_file(rows: list[dict[str, Any]], extra: list[dict[str, Any]], effects: tuple[str, ...],
                nuisances: dict[str, Any] | None = None) -> bytes:
    names = PAPER_EFFECTS + effects
    specs = {s.name: s for e in names for s in get_effect(e).params}
    values: dict[str, list[float]] = {}
    for row in rows:
        for k, v in row.items():
            if k in specs:  # clip into the spec range so the file loads (records keep the raw values)
                v = min(max(v, specs[k].low), specs[k].high) if not specs[k].periodic else v
            values.setdefault(k, []).append(v)
    theta = CaptureParams(values, effects=names, validate=False).wrapped()
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "truth.json"
        theta.save(path, extra=extra, metadata={"generator": _FORMAT, "version": _VERSION,
                                                "note": "true Θ per seed in patch units (σ in patch px)",
                                                **({} if nuisances is None else {"nuisances": nuisances})})
        return path.read_bytes()


def load_truth(path: str | os.PathLike) -> tuple[CaptureParams, list[dict[str, Any]], dict[str, Any]]:
    """The true Θ of a reference-camera seed set: ``(theta, per-seed extras, reference_camera header)``."""
    path = Path(path)
    theta, extra, _ = CaptureParams.load_with_extra(path / "truth.json")
    header = json.loads((path / "seedset.json").read_text())
    if "reference_camera" not in header:
        raise ValueError(f"{path}: not a reference-camera seed set (no 'reference_camera' in its header)")
    return theta, extra, header["reference_camera"]
