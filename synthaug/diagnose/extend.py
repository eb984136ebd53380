"""Extend a fit with an accepted candidate effect: the fitted Θ plus the effect, as a ``synthaug fit`` file.

The diagnosis (:func:`synthaug.diagnose.report.diagnose`) screens each
candidate with *camera-wide* settings φ (one value for every seed, as a
camera's are, blur radii in frame pixels). A generator works per seed in
patch units, so the accepted setting is written per seed through the same
conversion the screening used
(:func:`synthaug.diagnose.screening.extension_values`: a blur radius of
``s`` frame px is ``s / frame_scale_i`` patch px for seed i; a rolling-shutter
magnitude follows each seed's fitted motion direction α_m). Every fitted
parameter and every per-seed extra (``object_scale``, ``generator_seed``,
``distance``) is kept, so
:class:`~synthaug.data.synthetic.SyntheticObjectDataset` built on the new
file differs from one built on the base fit by exactly the added effect.

Example (shapes only; the fit and report come from ``synthaug fit`` and
``synthaug diagnose``)::

    from synthaug.diagnose.extend import extend_fit
    extend_fit("fits/drone_100_hog.json", "seeds/drone_100", "diagnosis/report.json",
               "fits/drone_100_hog_defocus.json")

Note that the albedo w_d stays the fitted one: the screening re-solves w_d
per seed for the base and the extended model alike (a nuisance, so that an
effect cannot win by fixing w_d), but the generator uses the fit's w_d.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Mapping

import torch

__all__ = ["extend_fit", "select_extension", "extension_rows"]

ReportLike = Mapping[str, Any] | str | os.PathLike


def select_extension(report_or_finding: ReportLike, *, use_top_screened: bool = False) -> dict[str, Any]:
    """The effect and camera-wide setting to add, from a report, a finding or a screened row.

    Args:
        report_or_finding: a diagnosis report (dict or path to ``report.json``),
            one of its ``findings``, or one of its ``screened`` rows.
        use_top_screened: with a report that has no effect finding, take the
            top-ranked screened candidate instead of raising (it is then
            marked ``significant: False``).

    Returns:
        ``{"effect", "setting", "space", "significant", "source"}``; ``space``
        is the distance space whose best setting is used (``"feature"`` when
        the candidate's channel is the detector's distance, ``"colour"`` for the
        chroma channel, else ``"pixel"``, as the report's extended samples do).

    Raises:
        ValueError: no effect finding (and not ``use_top_screened``), an
            ``unexplained`` finding, or an unknown effect.

    Example:
        >>> select_extension({"effect": "defocus", "setting": {"defocus_sigma": 0.8}, "significant": True,
        ...                   "channel": "distance:feature"})["setting"]
        {'defocus_sigma': 0.8}
    """
    from synthaug.diagnose.screening import CANDIDATE_GRIDS

    item: Any = report_or_finding
    if isinstance(item, (str, os.PathLike)):
        path = Path(item)
        try:
            item = json.loads(path.read_text())
        except FileNotFoundError:
            raise FileNotFoundError(f"diagnosis report not found: {path}") from None
        except json.JSONDecodeError as e:
            raise ValueError(f"{path}: not a JSON diagnosis report ({e})") from None
    if not isinstance(item, Mapping):
        raise ValueError(f"expected a diagnosis report, finding or screened row, got {type(item).__name__}")
    source = "finding"
    if "findings" in item:  # a whole report
        found = [f for f in item["findings"] if f.get("effect") != "unexplained"]
        if found:
            item = found[0]
        elif use_top_screened and item.get("screened"):
            item, source = item["screened"][0], "top_screened"
        else:
            what = [f.get("effect") for f in item["findings"]] or "none"
            raise ValueError(f"the report has no candidate-effect finding (findings: {what}); pass a screened row "
                             f"(report['screened'][0]) or use_top_screened=True to extend with the top-screened one")
    effect = item.get("effect")
    if effect == "unexplained":
        raise ValueError("an 'unexplained' finding names no effect to add; pass a screened row instead")
    if effect not in CANDIDATE_GRIDS:
        raise ValueError(f"unknown effect {effect!r}; candidates: {sorted(CANDIDATE_GRIDS)}")
    space = {"distance:feature": "feature", "distance:colour": "colour"}.get(item.get("channel"), "pixel")
    if space == "colour" and "setting" not in item and not item.get("setting_colour"):
        space = "pixel"
    if "setting" in item:
        setting = item["setting"]
    elif f"setting_{space}" in item:  # a screened row of report.json
        setting = item[f"setting_{space}"]
        source = "screened" if source == "finding" else source
    else:
        raise ValueError(f"no setting for {effect!r}: expected a finding ('setting') or a screened row "
                         f"('setting_feature'/'setting_pixel')")
    known = {k for s in CANDIDATE_GRIDS[effect] for k in s}
    if not isinstance(setting, Mapping) or set(setting) != known:
        raise ValueError(f"setting {setting!r} does not match the parameters of {effect!r} ({sorted(known)})")
    return {"effect": effect, "setting": {k: float(v) for k, v in setting.items()}, "space": space,
            "significant": bool(item.get("significant", False)), "source": source}


def extension_rows(theta: Any, frame_scale: torch.Tensor, effect: str, setting: Mapping[str, float],
                   object_px: torch.Tensor | None = None) -> dict[str, torch.Tensor]:
    """Per-seed parameters (patch units) of ``effect`` at the camera-wide ``setting``.

    Args:
        theta: the fitted :class:`~synthaug.params.CaptureParams` (N rows; α_m is read for rolling shutter).
        frame_scale: (N,) frame px per patch px of each seed (crop side / patch side).
        effect: candidate name.
        setting: camera-wide setting, as the screening's grids hold it.
        object_px: (N,) the object's size in frame px (haze's amount depends on it).

    Returns:
        ``{param: (N,) float64}`` for every parameter of the effect.

    Example:
        >>> from synthaug.params import CaptureParams
        >>> th = CaptureParams.default(2)
        >>> extension_rows(th, torch.tensor([2.0, 4.0]), "defocus", {"defocus_sigma": 1.0})["defocus_sigma"].tolist()
        [0.5, 0.25]
    """
    from synthaug.diagnose.screening import extension_values

    n = theta.batch_size
    fs = torch.as_tensor(frame_scale, dtype=torch.float64).reshape(-1)
    if fs.shape[0] != n:
        raise ValueError(f"frame_scale has {fs.shape[0]} values but the fit has {n} rows")
    if not bool(torch.isfinite(fs).all() and (fs > 0).all()):
        raise ValueError(f"frame_scale must be finite and > 0, got {fs.tolist()[:5]}...")
    if effect == "haze" and object_px is None:
        raise ValueError("haze needs each seed's object size in frame px (object_px)")
    # extension_values reads only ``frame_scale``, ``theta`` and ``object_px`` of a DiagnosisData
    data = SimpleNamespace(frame_scale=fs, theta=theta,
                           object_px=None if object_px is None else torch.as_tensor(object_px, dtype=torch.float64))
    values = extension_values(data, effect, dict(setting))[effect]
    return {k: torch.as_tensor(v, dtype=torch.float64).reshape(-1).expand(n).clone() for k, v in values.items()}


def extend_fit(
    fit_path: str | os.PathLike,
    seeds: Any,
    report_or_finding: ReportLike,
    out_path: str | os.PathLike,
    *,
    use_top_screened: bool = False,
    mesh: Any = None,
) -> Path:
    """Write the fit extended by the accepted effect (a CaptureParams file, ``synthaug fit`` format).

    Args:
        fit_path: the base fit (``synthaug fit`` output) the diagnosis ran on.
        seeds: its seed set (:class:`~synthaug.data.seedset.SeedSet` or folder): each seed's frame scale.
        report_or_finding: the diagnosis report (dict or ``report.json``) — its first effect finding is
            used —, a finding, or a screened row (see :func:`select_extension`).
        out_path: the file to write.
        use_top_screened: with a report without an effect finding, use the top-screened candidate.
        mesh: the fit's mesh: each seed's fitted w_d is then scaled by the ratio of the least-squares
            w_d with and without the effect (re-solved as the screening measures both models), so an
            intensity effect (haze, exposure, a gain) does not add to a w_d fitted without it, and the
            base fit's w_d is otherwise kept. None keeps the fitted w_d.

    Returns:
        ``out_path``. Its effects are the fit's plus the added one; its rows keep every fitted value and
        per-seed extra; its metadata keeps the fit's and adds ``extension`` (effect, camera-wide setting,
        space, significance, source, base fit).

    Raises:
        ValueError: no usable finding, unknown effect, an effect the fit already has, or a seed set
            whose size differs from the fit's.
    """
    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.reference_camera import seed_geometry
    from synthaug.effects.registry import get_effect
    from synthaug.params import CaptureParams

    ext = select_extension(report_or_finding, use_top_screened=use_top_screened)
    theta, extra, meta = CaptureParams.load_with_extra(fit_path)
    effect = ext["effect"]
    if effect in theta.effects:
        raise ValueError(f"{fit_path} already has the effect {effect!r} (effects {list(theta.effects)})")
    if isinstance(seeds, (str, os.PathLike)):
        seeds = SeedSet.load(seeds)
    if len(seeds) != theta.batch_size:
        raise ValueError(f"{fit_path} has {theta.batch_size} rows but the seed set has {len(seeds)} seeds")
    fs = seed_geometry(seeds)["frame_scale"].double()
    scale = torch.tensor([float(e.get("object_scale", meta.get("object_scale", 0.7))) for e in extra],
                         dtype=torch.float64)
    rows = extension_rows(theta, fs, effect, ext["setting"], object_px=scale * seeds.patch_size * fs)
    clipped = 0
    specs = {s.name: s for s in get_effect(effect).params}
    for name, v in rows.items():
        lo, hi = specs[name].low, specs[name].high
        clipped += int(((v < lo) | (v > hi)).sum())
        rows[name] = v.clamp(lo, hi)
    values = {k: v for k, v in theta.as_dict().items()}
    values.update({k: v.float() for k, v in rows.items()})
    w_note = "kept from the base fit"
    if mesh is not None:
        from synthaug.diagnose.diagnosis_data import load_diagnosis_data, solve_albedo

        data = load_diagnosis_data(seeds, fit_path, mesh)
        w_ext, w_base = solve_albedo(data, {effect: dict(rows)}), solve_albedo(data)
        ratio = torch.where(w_base > 1e-3, w_ext / w_base.clamp_min(1e-3), torch.ones_like(w_base))
        values["w_d"] = (theta.w_d[:, :1].double() * ratio.double().reshape(-1, 1)).clamp(0.0, 1.0).float()
        w_note = ("scaled per seed by w_d(extended) / w_d(base), both re-solved as screened: the fitted w_d "
                  "changed only by what the effect changes")
    out_theta = CaptureParams(values, channels=theta.channels, effects=tuple(theta.effects) + (effect,))
    metadata = dict(meta)
    metadata["extension"] = {**ext, "base_fit": str(fit_path), "clipped_values": clipped, "w_d": w_note,
                             "units": "per-seed patch units (blur radii: frame px / frame_scale)"}
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out_theta.save(out, extra=extra, metadata=metadata)
    return out
