"""``diagnose``: residual analysis + candidate screening → ranked findings, report.json and report.md.

Example (the shipped demo data with vignetting hidden; slow, so not run here)::

    from synthaug.diagnose.report import diagnose
    report = diagnose("seeds/", "quadcopter", "fit.json", out_dir="diagnosis/")
    report["findings"][0]["effect"]   # 'vignetting'

A finding is a candidate effect whose extension helps on held-out seeds
(significant after correction for the number of candidates; the second and
later findings are screened again on top of those before them, forward
selection, so one effect's gain is not reported twice under two names), or
``"unexplained"`` when the residual has significant structure that no
candidate explains, with that structure described. A clean case reports no
finding. After accepted findings, the residual of the extended model is
measured again: structure the accepted effects do not produce is reported as
a trailing ``"unexplained"`` finding.
"""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import torch

__all__ = ["diagnose", "HINTS", "REPORT_FORMAT", "left_unexplained", "structure_hints", "write_markdown"]

REPORT_FORMAT = "synthaug.diagnosis"

# Which residual structures point to which candidates (screened first, in this order).
HINTS: dict[str, tuple[str, ...]] = {
    "radial": ("vignetting", "lens_distortion", "chromatic_aberration"),
    "tone_curve": ("gamma", "exposure", "haze"),
    "noise_vs_signal": ("shot_noise",),
    "high_frequency": ("defocus", "sharpening", "shot_noise"),
    "block_8x8": ("compression",),
    "motion_direction": ("rolling_shutter",),
    "rotor_parts": ("rotor_blur",),
    "interior_bias": ("exposure", "haze", "specular", "white_balance"),
    "boundary_bias": ("defocus", "sharpening", "haze"),
    "periodic_rows": ("compression",),
    "periodic_columns": ("compression",),
    "column_pattern": ("compression",),
    "row_pattern": ("compression",),
}
BLOCK_GRID_STRUCTURES = ("periodic_rows", "periodic_columns", "column_pattern", "row_pattern")
"""Structures whose :data:`HINTS` hold only when they lie on a codec's 8-px block grid (:func:`structure_hints`)."""
BLOCK_GRID_TOLERANCE = 0.0125
"""Cycles per frame px a periodic structure's peak may sit from a multiple of 1/8 and still be the block grid's
(one step of the ``periodic_*`` measures' frequency grid)."""
_FITTED_PARAMS = ("sigma_s", "sigma_u", "sigma_n")
FRAME_EVIDENCE_CHANNELS = ("noise_level", "frame")
"""Screening channels read from the whole frames, not from the fitted patches: their evidence does not change with the
extensions the model already holds (:func:`_forward_selection`)."""
NLF_KEYS = ("slope", "t", "p", "n_seeds", "fitted_slope", "gain", "shot_sigma")
"""What the report keeps of the noise level function (:func:`synthaug.diagnose.noise.noise_channel`)."""


def structure_hints(name: str, measure: dict[str, Any]) -> tuple[str, ...]:
    """The candidate effects a residual structure points at: :data:`HINTS`, except that a line structure
    (:data:`BLOCK_GRID_STRUCTURES`) points at compression only when it is periodic on the 8-px block grid of a
    codec's transform (JPEG's and H.264's 8x8 and 4x4 blocks: a spectral peak at k/8 cycles per frame px,
    within :data:`BLOCK_GRID_TOLERANCE`). A sensor's column pattern with a 4.9-px period, or one with no period,
    is not a codec's, and no candidate explains it.

    Example:
        >>> structure_hints("periodic_columns", {"period_px": 8.0})
        ('compression',)
        >>> structure_hints("column_pattern", {"period_px": 4.9, "periodic": True})
        ()
        >>> structure_hints("column_pattern", {"period_px": 4.0, "periodic": False})
        ()
        >>> structure_hints("tone_curve", {})
        ('gamma', 'exposure', 'haze')
    """
    hints = HINTS.get(name, ())
    if name not in BLOCK_GRID_STRUCTURES:
        return hints
    period = measure.get("period_px")
    if measure.get("periodic") is False or period is None or not (np.isfinite(period) and period > 0):
        return ()
    k = 8.0 / float(period)  # the peak in units of 1/8 cycle per px
    on_grid = round(k) >= 1 and abs(k - round(k)) / 8.0 <= BLOCK_GRID_TOLERANCE + 1e-9
    return hints if on_grid else ()


def _order(structure: dict[str, dict[str, Any]], candidates: Sequence[str]) -> tuple[list[str], list[str]]:
    hinted: list[str] = []
    for name, m in sorted(structure.items(), key=lambda kv: kv[1]["p"]):
        if m.get("significant") or m["p"] < 0.01:
            hinted += [c for c in structure_hints(name, m) if c in candidates and c not in hinted]
    return hinted + [c for c in candidates if c not in hinted], hinted


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else None
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.bool_,)):
        return bool(x)
    if isinstance(x, torch.Tensor):
        return _jsonable(x.tolist())
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    return x


def _setting(row: dict[str, Any]) -> dict[str, float]:
    """The setting of a screened row: its channel's; a setting read off the whole frames wins whenever the frame
    channel is significant too (the frames' own read of the camera, not a grid point chosen by held-out patches)."""
    if row["channel"] == "noise_level" and row.get("noise_setting"):
        return row["noise_setting"]
    frame_significant = any(c["channel"] == "frame" and c["significant"] for c in row.get("channels") or [])
    if (row["channel"] == "frame" or frame_significant) and row.get("frame_setting"):
        return row["frame_setting"]
    if row["channel"] == "highlight" and row.get("highlight_setting"):
        return row["highlight_setting"]
    if row["channel"] == "distance:colour":
        return row["screen"]["colour"]["setting"]
    space = "feature" if row["channel"] == "distance:feature" else "pixel"
    return row["screen"][space]["setting"]


def _extended_render(data: Any, row: dict[str, Any], given: dict[str, Any] | None = None
                     ) -> tuple[torch.Tensor, dict[str, float]]:
    from synthaug.diagnose.diagnosis_data import render_with, solve_albedo
    from synthaug.diagnose.screening import extension_values, given_values

    setting = _setting(row)
    ext = {**given_values(data, given), **extension_values(data, row["effect"], setting)}
    w = solve_albedo(data, ext)
    return render_with(data, ext, w_d=w), setting


def _forward_selection(data: Any, order: list[str], *, k: int, seed: int, alpha: float, max_effects: int,
                       say: Callable[[str], None], asked: Sequence[str] | None = None
                       ) -> tuple[list[dict[str, Any]], list[tuple[dict, dict]]]:
    """Screen every candidate, accept the best significant one, re-screen the other significant ones on top
    of it (their conditional gain), and so on: an effect whose gain another one already explains drops out. A
    significant gain that another candidate explained better (:func:`~synthaug.diagnose.screening.explained_better`)
    is re-screened too, with that candidate: once the better explanation is accepted, it may stand on its own.

    The best significant one is the first by :func:`~synthaug.diagnose.screening._rank` (distance gains first),
    unless its distance gain is explained by a significant effect whose evidence comes from the whole frames
    (:data:`FRAME_EVIDENCE_CHANNELS`: the noise level function, the frame channel; the same whatever the model
    holds): re-screened on top of that effect at the setting the frames read, the top one is no longer
    significant. Then that effect is accepted first (and the other is re-screened on top of it, as any other).

    Returns:
        (rows of the first round, [(accepted row, the extensions it was screened on top of)]).
    """
    from synthaug.diagnose.screening import n_screening_tests, screen_candidates

    # the Bonferroni count of every candidate asked for (colour-only ones left out of gray data included): the
    # count the floors were calibrated with, so that leaving them out does not loosen the other tests
    n_tests = n_screening_tests(order if asked is None else asked)
    rows = screen_candidates(data, order, k=k, seed=seed, alpha=alpha, progress=lambda c: say(f"  {c}"),
                             n_tests=n_tests)
    first = rows
    # the NLF's rise is named once, on the base model (an accepted effect must not rename it in a later round)
    tone = next((r["tone"] for r in rows if r.get("tone")), None)
    accepted: dict[str, dict[str, float]] = {}
    picked: list[tuple[dict, dict]] = []
    while len(picked) < max_effects:
        sig = [r for r in rows if r["significant"] and r["effect"] not in accepted]
        if not sig:
            break
        top = sig[0]
        for r in sig[1:]:  # a distance gain that an effect evidenced by the whole frames already explains
            if not top["channel"].startswith("distance:") or r["channel"] not in FRAME_EVIDENCE_CHANNELS:
                continue
            again = screen_candidates(data, [top["effect"]], k=k, seed=seed, alpha=alpha, n_tests=n_tests, tone=tone,
                                      given={**accepted, r["effect"]: _setting(r)})
            if not again[0]["significant"]:
                say(f"{top['effect']}'s gain is explained by {r['effect']} ({r['channel']}): {r['effect']} first")
                top = r
                break
        picked.append((top, dict(accepted)))
        accepted[top["effect"]] = _setting(top)
        # screened again on top of it: the significant ones, and a gain another candidate explained better with
        # that candidate (screening.explained_better: with the better explanation accepted, the rest may stand)
        again_too = {e for r in rows for c in r.get("channels") or [] if c.get("explained_better_by")
                     for e in (r["effect"], c["explained_better_by"]["effect"])}
        rest = [r["effect"] for r in rows if r is not top and r["effect"] not in accepted
                and (r["significant"] or r["effect"] in again_too)]
        if not rest:
            break
        say(f"re-screening {rest} on top of {list(accepted)}")
        rows = screen_candidates(data, rest, k=k, seed=seed, alpha=alpha, given=accepted, n_tests=n_tests,
                                 tone=tone)
    return first, picked


def diagnose(
    seeds_dir: str | os.PathLike | Any,
    mesh: Any,
    fit_path: str | os.PathLike,
    *,
    distance: str = "hog",
    out_dir: str | os.PathLike | None = None,
    candidates: Sequence[str] | None = None,
    k: int = 5,
    seed: int = 0,
    alpha: float = 0.01,
    plots: bool = True,
    progress: Callable[[str], None] | None = None,
    max_effects: int = 3,
    gap: int = 0,
    gap_detectors: dict[str, Any] | None = None,
    object_colour: Sequence[float] | None = None,
) -> dict[str, Any]:
    """Diagnose a fitted simulation against its measured seed set.

    Args:
        seeds_dir: seed-set folder (or a loaded SeedSet).
        mesh: the mesh the fit used.
        fit_path: the fit file (``synthaug fit``).
        distance: the detector's distance (the fit's, normally).
        out_dir: where to write ``report.json``, ``report.md`` and plots (None: nothing written).
        candidates: candidate effects to screen (default: all).
        k: cross-validation folds.
        seed: seed of folds and permutation tests.
        alpha: family-wise significance level.
        plots: write the PNG plots with the markdown report.
        progress: called with a short message at each step.
        max_effects: at most this many effects are accepted by forward selection
            (each later one screened on top of those before it: ``given``).
        gap: when > 0, add the ``gap`` section (:func:`synthaug.diagnose.gap.gap_section`): the real seed
            patches against ``gap`` random-pose training samples of the fit per seed (``"training"``) and
            against each seed's best-fit render (``"fitted"``), in each detector family's features.
        gap_detectors: ``{family: detector or checkpoint}`` whose features the gap is measured in
            (default: HOG settings, random weak learners, an untrained seeded CNN).
        object_colour: the object's known colour, three positive RGB values of any scale (RGB seed sets only):
            the colour channel's model object takes it instead of a neutral grey, so a colour cast beyond it is
            the camera's (on the object alone a white balance and a paint read the same).

    Returns:
        the report: ``findings`` (ranked; each ``effect`` — a candidate name or
        ``"unexplained"`` —, ``significant``, ``evidence``, ``gains``),
        ``screened`` (every candidate), ``residuals`` (structure measures),
        ``parameter_dependence``, ``realism`` (real-vs-synthetic accuracy).
    """
    from synthaug.diagnose.diagnosis_data import load_diagnosis_data
    from synthaug.diagnose.screening import CANDIDATE_GRIDS, kfold, offered_candidates, realism_accuracy
    from synthaug.diagnose.screening import object_colour as read_object_colour

    t0 = time.perf_counter()
    say = progress or (lambda s: None)
    names = list(CANDIDATE_GRIDS) if candidates is None else list(candidates)
    bad = [c for c in names if c not in CANDIDATE_GRIDS]
    if bad:
        raise ValueError(f"unknown candidate(s) {bad}; candidates: {sorted(CANDIDATE_GRIDS)}")
    asked = list(names)
    if k < 2:
        raise ValueError(f"k must be >= 2 folds, got {k}")
    say("loading seeds and fitted layers")
    data = load_diagnosis_data(seeds_dir, fit_path, mesh, distance=distance)
    if object_colour is not None:
        from synthaug.diagnose.diagnosis_data import object_colour_factors

        data.object_rgb = object_colour_factors(object_colour)
        if data.real_rgb is None:
            raise ValueError(f"an object colour needs RGB seed patches (colour.npz); {data.colour_note or 'none'}")
    names, not_offered = offered_candidates(data, names)  # single-channel data: no colour-only candidate
    if len(data) < 2 * k:
        raise ValueError(f"need at least {2 * k} seeds for {k}-fold screening, got {len(data)}")
    say("residual analysis")
    res = _residual_analysis(data, np.random.default_rng(seed), alpha)
    order, hinted = _order(res["structure"], names)
    say(f"screening {len(order)} candidates")
    rows, picked = _forward_selection(data, order, k=k, seed=seed, alpha=alpha, max_effects=max_effects, say=say,
                                      asked=asked)
    folds = kfold(len(data), k, np.random.default_rng(seed + 1))
    acc_base = realism_accuracy(data, res["syn0"], folds)
    nlf = _noise_level_function(data, folds)
    findings, ext_images = _effect_findings(data, picked, folds, acc_base, res["structure"], hinted)
    remaining = _remaining_structure(data, picked, res["structure"], seed=seed, alpha=alpha)
    gap_report = None
    if gap:
        say(f"gap in the detectors' features ({gap} training samples per seed)")
        gap_report = _gap_report(data, res["syn0"], seeds_dir, mesh, fit_path, gap=gap, seed=seed,
                                 detectors=gap_detectors, out_dir=out_dir if plots else None)
    unexplained = _unexplained_finding(remaining, picked, findings)
    if unexplained is not None:
        findings.append(unexplained)
    report = {
        "format": REPORT_FORMAT, "version": 1,
        "inputs": {"seeds": str(getattr(seeds_dir, "path", seeds_dir)), "mesh": str(mesh), "fit": str(fit_path),
                   "distance": data.distance_name, "n_seeds": len(data), "k_folds": k, "seed": seed,
                   "alpha": alpha},
        "findings": findings,
        "significant": bool(findings),
        "screened": [_screened_row(r) for r in rows],
        **_residual_sections(data, res, hinted, not_offered),
        "noise_level_function": nlf,
        "realism": {"accuracy_base": acc_base,
                    "note": "k-fold accuracy of logistic regression on HOG, real vs fitted synthetic; 0.5 = "
                            "indistinguishable"},
        "seconds": time.perf_counter() - t0,
    }
    report["colour"]["object_colour"] = read_object_colour(data, folds)
    report["colour"]["object_rgb_given"] = None if data.object_rgb is None else [float(v) for v in data.object_rgb]
    if gap_report is not None:
        report["gap"] = gap_report
    report = _jsonable(report)
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        from synthaug.params import atomic_write_text

        figs = _plots(out, data, res["syn0"], ext_images, res["fmap"]) if plots else {}
        atomic_write_text(out / "report.json", json.dumps(report, indent=1))
        atomic_write_text(out / "report.md", write_markdown(report, figs))
    return report


def _residual_analysis(data: Any, rng: np.random.Generator, alpha: float) -> dict[str, Any]:
    """The base render's residual: its structure, the HOG residual map, and which fitted parameters depend on
    the seeds' metadata. Returns ``syn0`` (the base render), ``structure``, ``fmap`` and ``dependence``."""
    from synthaug.diagnose.residuals import (
        feature_residual_map,
        parameter_dependence,
        seed_groups,
        seed_metadata,
        structure_measures,
    )
    from synthaug.diagnose.screening import base_render

    syn0, w0 = base_render(data)
    structure = structure_measures(data, syn0, rng=rng, alpha=alpha)
    fmap = feature_residual_map(data, syn0)
    meta = seed_metadata(data)
    fitted = {"w_d": w0.double().numpy()}
    th = data.theta.as_dict()
    for p in _FITTED_PARAMS:
        fitted[p] = th[p][:, 0].double().numpy()
    dependence = parameter_dependence(fitted, {k_: v for k_, v in meta.items() if k_ != "inverse_size"}, rng=rng,
                                      alpha=alpha, groups=seed_groups(data))
    return {"syn0": syn0, "structure": structure, "fmap": fmap, "dependence": dependence}


def _residual_sections(data: Any, res: dict[str, Any], hinted: list[str], not_offered: Sequence[str] = ()
                       ) -> dict[str, Any]:
    """The report's sections on the base residual, its colour (and the colour-only candidates not offered on
    single-channel data) and the significance rule."""
    from synthaug.diagnose.calibration import describe as describe_floors, rule_text
    from synthaug.diagnose.screening import BLUR_RULE, OBJECTS_RULE, RIVAL_RULE

    fmap = res["fmap"]
    return {
        "residuals": res["structure"],
        "feature_residuals": None if fmap is None else {
            "mean_per_block": fmap["mean"], "block_stride_px": fmap["cell_px"], "share_centre": fmap["share_centre"],
            "note": "mean over seeds of |HOG block(real) - HOG block(synthetic)| at each block position of the "
                    "object-centred patch: where the detector sees the difference"},
        "hinted_candidates": hinted,
        "colour": {"screened": data.real_rgb is not None, "note": data.colour_note,
                   "not_offered": list(not_offered)},
        "significance": {"rule": f"{rule_text()} {OBJECTS_RULE} {BLUR_RULE} {RIVAL_RULE}",
                         "calibration": describe_floors()["source"]},
        "parameter_dependence": [d for d in res["dependence"] if d["significant"]],
    }


def _noise_level_function(data: Any, folds: Any) -> dict[str, Any] | None:
    """The frames' noise-level function off the object (None without measured noise levels)."""
    if data.noise_levels is None:
        return None
    from synthaug.diagnose.noise import noise_channel

    nc = noise_channel(data.noise_levels, folds)
    nlf = {k_: nc[k_] for k_ in NLF_KEYS}
    nlf["note"] = ("log-log slope of the frames' noise variance vs brightness, off the object (0: read noise "
                   "only, as the model's sigma_n assumes; > 0: shot noise, or an expansive tone curve (g > 1), "
                   "told apart by the patches' tone; < 0: a compressive tone curve after the sensor); gain: "
                   "held-out log-likelihood of the power-law NLF over a flat one, nats/px")
    return nlf


def _effect_findings(data: Any, picked: list[tuple[dict, dict]], folds: Any, acc_base: float,
                     structure: dict[str, dict[str, Any]], hinted: list[str]
                     ) -> tuple[list[dict[str, Any]], tuple[str, torch.Tensor] | None]:
    """One finding per accepted effect (its gains and evidence), and the first one's extended render."""
    from synthaug.diagnose.screening import realism_accuracy

    findings: list[dict[str, Any]] = []
    ext_images = None
    for rank, (row, given) in enumerate(picked):
        syn1, setting = _extended_render(data, row, given)
        if rank == 0:
            ext_images = (row["effect"], syn1)
        acc = realism_accuracy(data, syn1, folds)
        sc = row["screen"]
        findings.append({
            "effect": row["effect"], "significant": True, "channel": row["channel"], "score": row["score"],
            "p_adjusted": row["p_adjusted"], "setting": setting, "given": list(given),
            "gains": {"heldout_feature": sc["feature"]["gain"], "heldout_pixel": sc["pixel"]["gain"],
                      "absorbed_parameter_r2": None if row["absorption"] is None else row["absorption"]["gain"],
                      "noise_loglik_per_px": None if row.get("noise") is None else row["noise"]["gain"],
                      "heldout_colour": sc["colour"]["gain"] if "colour" in sc else None,
                      "frame_statistic": next((c["gain"] for c in row["channels"] if c["channel"] == "frame"), None),
                      "highlight_k": next((c["gain"] for c in row["channels"] if c["channel"] == "highlight"), None),
                      "realism_accuracy_before": acc_base, "realism_accuracy_after": acc},
            "evidence": {"channels": row["channels"], "absorption": row["absorption"],
                         "noise_level_function": None if row.get("noise") is None else {
                             k_: row["noise"][k_] for k_ in NLF_KEYS},
                         "hinted_by_residuals": row["effect"] in hinted,
                         "residual_structure": [m["description"] for n_, m in structure.items()
                                                if m["significant"] and row["effect"] in structure_hints(n_, m)]},
        })
    return findings, ext_images


def _remaining_structure(data: Any, picked: list[tuple[dict, dict]], structure: dict[str, dict[str, Any]], *,
                         seed: int, alpha: float) -> dict[str, dict[str, Any]]:
    """The residual of the extended model: structure the accepted effects do not explain (``structure`` when
    none was accepted)."""
    from synthaug.diagnose.residuals import structure_measures
    from synthaug.diagnose.screening import base_render

    if not picked:
        return structure
    accepted = {r["effect"]: _setting(r) for r, _ in picked}
    syn_acc = base_render(data, accepted)[0]
    remaining = structure_measures(data, syn_acc, rng=np.random.default_rng(seed + 2), alpha=alpha)
    return left_unexplained(remaining, accepted)


def left_unexplained(structure: dict[str, dict[str, Any]], accepted: Sequence[str]) -> dict[str, dict[str, Any]]:
    """The residual structures that none of the ``accepted`` effects explains (:func:`structure_hints`).

    Example:
        >>> s = {"block_8x8": {"p": 1e-6}, "column_pattern": {"p": 1e-5, "period_px": 4.9, "periodic": True}}
        >>> sorted(left_unexplained(s, ["compression"]))
        ['column_pattern']
    """
    return {n_: m for n_, m in structure.items() if not set(structure_hints(n_, m)) & set(accepted)}


def _gap_report(data: Any, syn0: torch.Tensor, seeds_dir: Any, mesh: Any, fit_path: str | os.PathLike, *,
                gap: int, seed: int, detectors: dict[str, Any] | None,
                out_dir: str | os.PathLike | None) -> dict[str, Any]:
    """The ``gap`` section: the real patches against ``gap`` training samples per seed and the fitted renders."""
    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.gap import gap_section, training_samples

    seedset = SeedSet.load(seeds_dir) if isinstance(seeds_dir, (str, os.PathLike)) else seeds_dir
    seed_of = np.arange(len(data))  # folds hold a seed's real and synthetic patches out together
    return gap_section(data.real, {"training": training_samples(seedset, mesh, fit_path, gap * len(data), seed=seed),
                                   "fitted": (syn0, seed_of)},
                       real_groups=seed_of, detectors=detectors, seed=seed, out_dir=out_dir)


def _unexplained_finding(remaining: dict[str, dict[str, Any]], picked: list[tuple[dict, dict]],
                         findings: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The ``"unexplained"`` finding: significant structure left in the residual (None when there is none)."""
    sig_struct = {n_: m for n_, m in remaining.items() if m["significant"] and n_ != "background_bias"}
    if not sig_struct:
        return None
    return {
        "effect": "unexplained", "significant": True,
        "structure": {n_: {"description": m["description"], "p": m["p"], "value": m["value"],
                           **{kk: m[kk] for kk in ("frequency", "period_px", "amplitude", "periodic") if kk in m}}
                      for n_, m in sig_struct.items()},
        "evidence": {"note": ("the residual has significant structure, and no candidate's extension helps "
                              "on held-out seeds") if not picked else
                     (f"structure left in the residual after adding {', '.join(f['effect'] for f in findings)}, "
                      "of a kind those effects do not produce")},
        "gains": {},
    }


def _absorbed_text(f: dict[str, Any]) -> str:
    """The absorbed channel's evidence, for a finding's line of report.md."""
    ab = f["evidence"].get("absorption") or {}
    text = f"; absorbed-parameter R² {f['gains']['absorbed_parameter_r2']:.2f}"
    if ab.get("parameter") is None:
        return text
    stat = {"pearson": "Pearson r", "spearman": "Spearman ρ"}.get(ab.get("statistic"), "Spearman ρ")
    within = " within videos" if ab.get("within") else ""
    return text + f" ({ab['parameter']} vs {ab['metadata']}{within}: {stat} {ab['rho']:+.2f}, p = {ab['p']:.2g})"


def _frame_text(f: dict[str, Any]) -> str:
    """The frame channel's evidence, for a finding's line of report.md."""
    ch = next((c for c in f["evidence"]["channels"] if c["channel"] == "frame"), None)
    if ch is None:
        return ""
    floor = "none" if ch["floor"] is None else f"{ch['floor']:.3g}"
    where = f"over {ch['scenes']} distinct scenes ({ch['frames']} frames; clean floor {floor})"
    if f["effect"] == "vignetting":
        return (f"; the whole frames fall off toward the corners: log fall-off {ch['log_slope']:+.3f} {where}, a "
                f"gain 1 - {ch['gain']:.2f} r²; on the object the fitted w_d absorbs it")
    if f["effect"] == "sharpening":
        return (f"; the whole frames' edges are steeper than clean frames': the step across an edge between ±2 px "
                f"is {ch['gain']:.1%} of that between ±4 px (clean mean {ch['centre']:.1%}) {where}; read on the "
                "frames at edges found on their independent background frames")
    if f["effect"] == "lens_distortion":
        kind = "barrel" if ch["k1"] < 0 else "pincushion"
        return (f"; the scene's motion between the frames and their independent background frames is not one shift: "
                f"it reads a radial distortion k₁ {ch['k1']:+.3f} ({kind}, division model; |k₁| tested) {where}")
    q = ch.get("jpeg_quality")
    return (f"; the whole frames carry an 8x8 block grid: steps across its lines {math.exp(ch['gain']):.2f}x those "
            f"inside the blocks beside them (median over the lines) {where}"
            + (f"; their blocks' DCT coefficients sit on the steps of JPEG quality {q:.0f}" if q is not None else
               "; their blocks' DCT coefficients show no JPEG table (another codec's transform)"))


def _highlight_text(f: dict[str, Any]) -> str:
    """The highlight channel's evidence, for a finding's line of report.md."""
    ch = next((c for c in f["evidence"]["channels"] if c["channel"] == "highlight"), None)
    if ch is None:
        return ""
    centre = "0" if ch["centre"] is None else f"{ch['centre']:.3f}"
    floor = "none" if ch["floor"] is None else f"{ch['floor']:.3f}"
    return (f"; the objects carry a highlight the model's diffuse shading does not: amplitude k = {ch['gain']:.3f} ± "
            f"{ch['se']:.3f} of a specular lobe (exponent {ch['setting']['specular_shininess']:g}) fitted with the "
            f"albedo over {ch['seeds']} seeds (clean materials: mean {centre}, floor {floor}); an appearance of the "
            "object (a glossy paint), not of the camera")


def _screened_row(r: dict[str, Any]) -> dict[str, Any]:
    """One candidate's row of the report's ``screened`` list."""
    sc = r["screen"]
    return {kk: r[kk] for kk in ("effect", "significant", "channel", "score", "p_adjusted", "gain")} | {
        "setting_feature": sc["feature"]["setting"], "setting_pixel": sc["pixel"]["setting"],
        "setting_colour": sc["colour"]["setting"] if "colour" in sc else None,
        "gain_colour": sc["colour"]["gain"] if "colour" in sc else None,
        "colour_skipped": sc.get("colour_skipped"),
        "gain_feature": sc["feature"]["gain"], "gain_pixel": sc["pixel"]["gain"],
        "absorption": r["absorption"], "channels": r["channels"]}


def _plots(out: Path, data: Any, syn0: torch.Tensor, ext: tuple[str, torch.Tensor] | None,
           fmap: dict[str, Any] | None = None) -> dict[str, str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from synthaug.diagnose.residuals import aligned_maps

    figs: dict[str, str] = {}
    res = data.real - syn0
    maps = aligned_maps(res)
    fig, ax = plt.subplots(1, 4 if fmap is not None else 3, figsize=(13.5 if fmap is not None else 10, 3.2))
    v = float(np.abs(maps["mean"]).max()) or 1e-3
    im = ax[0].imshow(maps["mean"], cmap="RdBu_r", vmin=-v, vmax=v)
    ax[0].set_title("mean residual (real - syn)")
    fig.colorbar(im, ax=ax[0], fraction=0.046)
    im = ax[1].imshow(maps["rms"], cmap="magma")
    ax[1].set_title("RMS residual")
    fig.colorbar(im, ax=ax[1], fraction=0.046)
    obj = (data.coverage > 0.5)[:, 0]
    x = syn0[:, 0][obj].numpy()
    y = res[:, 0][obj].numpy()
    bins = np.linspace(0, 1, 11)
    idx = np.digitize(x, bins) - 1
    centres, means, sds = [], [], []
    for b in range(10):
        sel = idx == b
        if sel.sum() > 20:
            centres.append((bins[b] + bins[b + 1]) / 2)
            means.append(y[sel].mean())
            sds.append(y[sel].std())
    ax[2].errorbar(centres, means, yerr=sds, marker="o", capsize=2)
    ax[2].axhline(0, color="k", lw=0.5)
    ax[2].set_xlabel("fitted intensity (object)")
    ax[2].set_ylabel("residual")
    ax[2].set_title("intensity curve")
    if fmap is not None:
        im = ax[3].imshow(fmap["mean"], cmap="magma")
        ax[3].set_title(f"HOG residual per block ({fmap['cell_px']} px)")
        fig.colorbar(im, ax=ax[3], fraction=0.046)
    fig.tight_layout()
    fig.savefig(out / "residuals.png", dpi=90)
    plt.close(fig)
    figs["residuals"] = "residuals.png"
    n = min(8, len(data))
    rows = [data.real[:n], syn0[:n]] + ([ext[1][:n]] if ext is not None else [])
    grid = torch.cat([torch.cat(list(r[:, 0]), dim=1) for r in rows], dim=0).clamp(0, 1).numpy()
    fig, ax = plt.subplots(figsize=(1.2 * n, 1.3 * len(rows)))
    ax.imshow(grid, cmap="gray", vmin=0, vmax=1)
    ax.set_yticks([(i + 0.5) * data.real.shape[-1] for i in range(len(rows))])
    ax.set_yticklabels(["real", "fitted"] + ([f"+ {ext[0]}"] if ext is not None else []))
    ax.set_xticks([])
    ax.set_title(f"first {n} seeds: real patch and its best-fit synthetic image", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "samples.png", dpi=90)
    plt.close(fig)
    figs["samples"] = "samples.png"
    return figs


def _tone_text(f: dict[str, Any]) -> str:
    """A noise-level finding's tone evidence (a rising NLF: tone curve or shot noise), for the markdown."""
    if f.get("channel") != "noise_level":
        return ""
    ch = next((c for c in f["evidence"]["channels"] if c.get("channel") == "noise_level"), {})
    tone, shape = ch.get("tone"), ch.get("shape")
    if shape and shape.get("explains"):
        what = ("a power law (a tone curve after the sensor)" if shape["explains"] == "gamma"
                else "a linear rise over a floor (shot noise over read noise)")
        return (f"; the rise's shape decides: {what} fits the held-out seeds' noise better "
                f"({shape['gain']:+.5f} nats per pixel; {shape['positive']} of {shape['n']} seeds prefer the power "
                f"law, p = {shape['p']:.1g})")
    if not tone:
        return ""
    return (f"; the tone curve this rise implies (g = {tone['implied_gamma_g']:.2f}) "
            f"{'lowers' if tone['gain'] > 0 else 'raises'} the pixel distance to the real patches by "
            f"{100 * abs(tone['gain']):.1f} % (t = {tone['t']:.1f}): "
            + ("the signal's tone changed, a tone curve" if tone["explains"] == "gamma" else
               "the signal's tone is unchanged, added noise"))


def write_markdown(report: dict[str, Any], figs: dict[str, str] | None = None) -> str:
    """The human report (markdown) of a diagnosis report dict."""
    figs = figs or {}
    inp = report["inputs"]
    lines = ["# Diagnosis of the fitted simulation", "",
             f"Seeds `{inp['seeds']}` ({inp['n_seeds']}), mesh `{inp['mesh']}`, fit `{inp['fit']}`, "
             f"distance `{inp['distance']}`, {inp['k_folds']}-fold held-out screening, α = {inp['alpha']}.", ""]
    if report.get("significance"):
        lines += [report["significance"]["rule"], ""]
    if not report["findings"]:
        beaten = any(c.get("explained_better_by") for r in report.get("screened") or []
                     for c in r.get("channels") or [])
        lines += ["**Nothing significant**: the residual between the real seeds and their fitted synthetic images "
                  "reads as fitting noise, and no candidate effect improves held-out seeds significantly"
                  + (" (a significant gain that another candidate explains better names nothing: see below)."
                     if beaten else "."), ""]
    else:
        lines += ["## Findings", ""]
        for i, f in enumerate(report["findings"], 1):
            if f["effect"] == "unexplained":
                lines += [f"{i}. **unexplained** — the residual has structure no candidate explains:"]
                lines += [f"   - {v['description']} (p = {v['p']:.2g})" for v in f["structure"].values()]
                continue
            g = f["gains"]
            acc = g.get("realism_accuracy_after")
            lines.append(
                f"{i}. **{f['effect']}** ({f['channel']}, z = {f['score']:.1f}, p_adj = {f['p_adjusted']:.2g}); "
                f"setting {f['setting']}; held-out gain {100 * (g['heldout_feature'] or 0):.1f} % "
                f"({inp['distance']}), {100 * (g['heldout_pixel'] or 0):.1f} % (pixels)"
                + (_absorbed_text(f) if f["channel"] == "absorbed" else "")
                + (f"; held-out chroma (R-G, B-G) gain {100 * g['heldout_colour']:.1f} %"
                   if g.get("heldout_colour") is not None else "")
                + ("; the colour channel assumes a neutral (grey) object: a coloured paint reads as a colour cast "
                   "(see the object's colour below)" if f["channel"] == "distance:colour" else "")
                + (f"; noise level function log-log slope {f['evidence']['noise_level_function']['slope']:+.2f} "
                   f"(flat = read noise only), held-out likelihood gain {g['noise_loglik_per_px']:.4f} nats/px"
                   if f["channel"] == "noise_level" else "")
                + (f"; σ_shot {f['setting']['shot_sigma']:.3f} from the frames' affine noise level function "
                   "(var = a + σ_shot² I, a per frame)"
                   if f["channel"] == "noise_level" and "shot_sigma" in f["setting"] else "")
                + (_frame_text(f) if f["channel"] == "frame" else "")
                + (_highlight_text(f) if f["channel"] == "highlight" else "")
                + _tone_text(f)
                + (f"; real-vs-synthetic accuracy {100 * g['realism_accuracy_before']:.0f} % → {100 * acc:.0f} %"
                   if acc is not None else "")
                + (f"; gains measured on top of {', '.join(f['given'])}" if f.get("given") else ""))
        lines.append("")
    lines += ["## Residual structure", "", "| measure | value | p | clean range / floor | significant | description |",
              "|---|---|---|---|---|---|"]
    for name, m in report["residuals"].items():
        fl = m.get("floor")
        fl_s = (f"[{fl[0]:.3g}, {fl[1]:.3g}]" if isinstance(fl, list) else f"|v| ≥ {fl:.3g}" if fl else "")
        lines.append(f"| {name} | {m['value']:.3g} | {m['p']:.2g} | {fl_s} | {'yes' if m['significant'] else ''} | "
                     f"{m['description']} |")
    fr = report.get("feature_residuals")
    if fr:
        lines += ["", f"Feature space (HOG): {100 * fr['share_centre']:.0f} % of the squared block residual lies in "
                  "the central blocks (the object); the map is the 4th panel of `residuals.png`."]
    nlf = report.get("noise_level_function")
    if not nlf:
        lines += ["", "Camera noise: not measurable from these seed frames (no second, independent look at the scene "
                  "off the object with noise above 0.3 grey levels: an ingested background fills only the object "
                  "region, and a video codec copies static blocks from frame to frame)."]
    else:
        lines += ["", f"Camera noise, measured on the frames off the object ({nlf['n_seeds']} seeds with a measurable "
                  f"brightness range): mean log-log slope of the noise variance vs brightness {nlf['slope']:+.2f} "
                  f"(t = {nlf['t']:.1f}, p = {nlf['p']:.2g}{'' if nlf['p'] < 0.01 else ': no evidence of a slope'}; "
                  "0 = read noise only, 1 = shot noise, < 0 = a compressive tone curve after the sensor)."]
    lines += ["", "## Fitted parameters vs seed metadata (significant only)", ""]
    deps = report["parameter_dependence"]
    lines += [f"- {d['parameter']} vs {d['metadata']}: Spearman ρ = {d['rho']:+.2f} (p = {d['p']:.2g})"
              for d in deps] or ["- none"]
    lines += ["", "## All candidates (held-out, penalised gains)", "",
              "| effect | significant | channel | z | gain (feature) | gain (pixels) | gain (chroma) |",
              "|---|---|---|---|---|---|---|"]
    for r in report["screened"]:
        z = r["score"] if r["score"] is not None else -math.inf
        gc = r.get("gain_colour")
        lines.append(f"| {r['effect']} | {'yes' if r['significant'] else ''} | {r['channel']} | {z:.1f} | "
                     f"{100 * (r['gain_feature'] or 0):.2f} % | {100 * (r['gain_pixel'] or 0):.2f} % | "
                     + (f"{100 * gc:.2f} % |" if gc is not None else "|"))
    for r in report["screened"]:
        for ch in (c for c in r.get("channels") or [] if c.get("explained_better_by")):
            eb = ch["explained_better_by"]
            lines += ["", f"{r['effect'].capitalize()}'s {ch['channel']} gain ({100 * ch['gain']:.1f} % held out) "
                      f"passed its test but does not name it: `{eb['effect']}` explains the same distance better "
                      f"({100 * eb['gain']:.1f} %), so the evidence does not point at {r['effect']}."]
        ch = next((c for c in r.get("channels") or [] if c.get("radial_veto")), None)
        if ch is not None:
            lines += ["", f"{r['effect'].capitalize()} is not named from the frames: their edges steepen toward the "
                      f"corners (edge sharpness trend {ch['radial']:+.3f} per unit r² over scenes, clean frames ≤ "
                      f"{ch['radial_floor']:.3f}), a change of the image's scale with the distance from the centre "
                      "as a lens gives, where a sharpening steepens every edge alike."]
        ch = next((c for c in r.get("channels") or [] if c.get("objects_veto")), None)
        if ch is not None:
            obj = ", ".join(f"{k.split(':')[1]} {100 * v['gain']:+.1f} % (clean cases up to "
                            f"{100 * v['clean_upper']:+.1f} %)" for k, v in ch["objects"]["spaces"].items())
            lines += ["", f"{r['effect'].capitalize()} is not named from the frames: their edges are steeper than "
                      f"clean frames', but rendering it does not fit the objects better than it fits clean ones "
                      f"(held-out gain {obj}); an in-camera {r['effect']} filters the object as well, so the "
                      "frames' edges point at something else (a lens's change of scale steepens them too)."]
        vetoed = [c for c in r.get("channels") or [] if c.get("frames_veto")]
        if vetoed:
            fb = vetoed[0]["frames_veto"]
            gains = ", ".join(f"{c['channel']} {100 * c['gain']:+.1f} %" for c in vetoed)
            undone = f", read through the tone curve γ {fb['tone_undone']:.2f} undone" if fb.get("tone_undone") else ""
            lines += ["", f"{r['effect'].capitalize()} is not named: rendering it fits the objects better ({gains}), "
                      "but the whole frames' edges are not blurrier than clean frames' (edge sharpness "
                      f"{fb['ratio']:.3f} over {fb['scenes']} scenes{undone}, clean mean {fb['centre']:.3f}: "
                      f"t {fb['t']:+.1f}, one-sided p of a blur {fb['p_blurrier']:.2g} ≥ {fb['alpha']:.2g}). "
                      f"A {r['effect']} blurs the scene as it blurs the object; the objects' extra blur is their own "
                      "(their material or shape, a tone curve bending their facets)."]
        ch = next((c for c in r.get("channels") or [] if c.get("corroborated_by")), None)
        if ch is not None:
            from synthaug.diagnose.calibration import HAND_MIN_GAIN

            cb = ch["corroborated_by"]
            lines += ["", f"The lens (`{r['effect']}`) is named from its {ch['channel']} gain of "
                      f"{100 * ch['raw_gain_all']:.1f} %, under the {100 * HAND_MIN_GAIN:.0f} % an extension is "
                      "otherwise asked to give, "
                      f"because the whole frames show it: their edges steepen toward the corners (edge sharpness "
                      f"trend {cb['value']:+.3f} per unit r² over scenes, clean frames ≤ {cb['floor']:.3f}), and the "
                      "lens changes little of an object near the centre of the frame."]
    col = report.get("colour") or {}
    oc = col.get("object_colour")
    if oc:
        lines += ["", f"Object colour (an appearance reading, not a finding): the model's neutral grey object "
                  f"painted at chroma {oc['setting']['paint_saturation']:.3f}, hue "
                  f"{oc['setting']['paint_hue_deg']:.0f}° (0° red, 180° blue) fits the seeds best, held-out chroma "
                  f"gain {100 * oc['gain']:.1f} % (p = {oc['p']:.2g}). On the object alone the camera's white balance "
                  "reads as a paint along the colour-temperature axis (near 0° or 180°): a white-balance finding "
                  "there may be the object's own colour"
                  + (" (here the object's colour was given: the colour channel's model object has RGB factors "
                     + ", ".join(f"{v:.3f}" for v in col["object_rgb_given"]) + ")"
                     if col.get("object_rgb_given") else "; give it (`--object-colour R G B`) to tell them apart")
                  + ". Haze and chromatic aberration are named only where, on a painted object, they explain the "
                  "colour better than such a paint alone on held-out seeds."]
    if col and not col.get("screened"):
        skipped = [r["effect"] for r in report["screened"] if r.get("colour_skipped")]
        gone = col.get("not_offered") or []
        lines += ["", f"Colour statistics skipped ({col.get('note')})"
                  + (f": {', '.join(gone)} not screened (colour-only: a single channel has no lateral colour shift "
                     "and no colour cast)" if gone else "")
                  + (f"{';' if gone else ':'} {', '.join(skipped)} screened in gray only (feature and pixel "
                     "distances)" if skipped else "") + "."]
    lines += ["", f"Real-vs-synthetic classifier accuracy (fitted model): "
              f"{100 * report['realism']['accuracy_base']:.0f} % (50 % = indistinguishable).", ""]
    if report.get("gap"):
        from synthaug.diagnose.gap import gap_markdown

        lines += gap_markdown(report["gap"])
    for key, title in (("residuals", "Residual maps and intensity curve"), ("samples", "Samples: real / fitted / "
                                                                                        "extended")):
        if key in figs:
            lines += [f"### {title}", "", f"![{key}]({figs[key]})", ""]
    lines.append(f"_Diagnosis took {report['seconds']:.0f} s._")
    return "\n".join(lines) + "\n"
