"""Significance floors of the diagnosis, measured on clean nuisance-varied data (issue 20, item 3).

A diagnosis must stay quiet on data where nothing is missing from the model but
everything else differs, as with any real camera and object: another material
and light, another mesh, a scene that moves. Statistical tests alone do not
ensure that — with 60 seeds a systematic shading mismatch is "significant" —
so every statistic that can raise a finding must also leave the range that
clean data give it. That range is measured, not set by hand:

**The rule** (applied by :func:`synthaug.diagnose.residuals.structure_measures`
to every residual structure measure, for the first residual and for what is
left after accepted findings alike, and by
:func:`synthaug.diagnose.screening.screen_candidates` to every candidate's
channels):

1. its test rejects "no effect" at the family-wise level α (Bonferroni over
   the statistics of its kind), and
2. its value lies outside the null range of that statistic: over N clean
   nuisance-varied measured seed sets (``benchmarks/bench_diagnose_null.py``:
   reference camera with :meth:`~synthaug.diagnose.nuisances.Nuisances.draw`,
   nothing hidden, fitted, diagnosed),
   ``[min(min(μ, 0) - zσ, min), max(max(μ, 0) + zσ, max)]`` for a residual
   measure (either sign is a finding) and ``max(max(μ, 0) + zσ, max)`` for a
   candidate channel's held-out gain (distance channels: the penalised held-out
   relative gain; absorbed: the held-out R², counted as −|R²| where the dependence has the wrong sign, since
   only the sign the effect predicts can name it; noise level: the log-log slope in
   the candidate's direction; frame: the frames' radial fall-off k for vignetting, the log ratio of their steps
   across the 8x8 grid's lines to those inside the blocks beside them, median over lines, the smaller of columns
   and rows, for compression, their edges' step at ±2 px over that at ±4 px for sharpening), μ and
   σ the clean cases' mean and standard
   deviation, z = Φ⁻¹(1 - 0.05 / (s·M)) for M calibrated statistics (s = 2
   two-sided, 1 one-sided): if the null values are normal, a clean case raises
   a finding with probability ≤ 5 %. The null family holds both the nuisance
   mismatch (mean μ) and a model that is exactly right (mean 0), so data
   without nuisances are no finding either.

A statistic without a physical zero (the frames' edge sharpness: every camera's edges have some) is tested
against the clean cases' mean μ instead of 0 (``CENTRE`` of the calibration, :func:`gain_centre`); without a
calibrated centre it cannot be tested and raises nothing.

Besides significance, a distance channel's extension must be worth having: its
raw relative gain over all seeds must reach ``min_gain`` (2 %,
:data:`HAND_MIN_GAIN`) — a stated utility choice, not a significance floor.

The colour channel's held-out chroma gains (``distance:colour``) have their own clean null: colour cases of the
reference camera (RGB, a bluish sky, the object painted near-neutral by the nuisances), floors by the same rule
with z for the statistics a colour case holds (the gray ones and these). Statistics the calibration has no null for
(a statistic absent from the file) keep the hand-set floors
(:data:`HAND_FLOORS`, :data:`HAND_MIN_GAIN`, the noise module's slope floor),
and :func:`describe` says which are which. The floors live in
:mod:`synthaug.diagnose.null_floors`, written by the benchmark with the command
that produced them and its date; they hold for seed sets of about the size
calibrated (a statistic that is a mean over seeds varies less with more seeds,
so larger seed sets are treated conservatively).
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import math
from pathlib import Path
from typing import Any, Iterator, Sequence

__all__ = ["HAND_FLOORS", "HAND_MIN_GAIN", "structure_significant", "gain_floor", "gain_centre", "gain_upper",
           "rule_text",
           "one_sided_floor", "clean_upper",
           "describe", "derive_floors", "write_floors_module", "FAMILY_RATE", "hand_set"]

# The floors set by hand before the calibration (and the fallback for statistics without a null).
HAND_FLOORS: dict[str, float] = {
    "interior_bias": 0.03, "boundary_bias": 0.03, "background_bias": 0.03, "radial": 0.5, "tone_curve": 0.3,
    "noise_vs_signal": 0.02, "high_frequency": 0.7, "block_8x8": 0.3, "motion_direction": 0.5,
    "periodic_rows": 0.7, "periodic_columns": 0.7, "rotor_parts": 0.05, "column_pattern": 0.5, "row_pattern": 0.5,
}
HAND_MIN_GAIN = 0.02  # the smallest raw relative gain over all seeds worth an extension (utility, not significance)
FAMILY_RATE = 0.05  # the false-alarm rate per clean case the floors are set for


_HAND_SET_ONLY: list[bool] = [False]  # set within hand_set() only


@contextlib.contextmanager
def hand_set() -> Iterator[None]:
    """Within this block the hand-set floors apply everywhere (the rule before the calibration): to measure
    the old rule's false-alarm rate on the same data.

    Example:
        >>> with hand_set():
        ...     describe()["source"]
        'hand-set'
    """
    _HAND_SET_ONLY.append(True)
    try:
        yield
    finally:
        _HAND_SET_ONLY.pop()


def _floors() -> Any:
    if _HAND_SET_ONLY[-1]:
        return None
    try:
        from synthaug.diagnose import null_floors
    except ImportError:  # no calibration written yet
        return None
    return null_floors


def structure_significant(name: str, value: float, p: float, alpha_per_test: float) -> tuple[bool, Any]:
    """Whether a residual structure measure counts (the rule above), and the floor used.

    Returns:
        (significant, floor): floor is ``[lo, hi]`` (calibrated null range) or a hand-set ``float`` (|value|
        must reach it).
    """
    nf = _floors()
    rng = None if nf is None else nf.STRUCTURE.get(name)
    if not (math.isfinite(value) and math.isfinite(p)):
        return False, rng if rng is not None else HAND_FLOORS.get(name, 0.0)
    if rng is not None:
        lo, hi = rng
        return bool(p < alpha_per_test and not lo <= value <= hi), [float(lo), float(hi)]
    floor = HAND_FLOORS.get(name, 0.0)
    return bool(p < alpha_per_test and abs(value) >= floor), floor


def gain_floor(effect: str, channel: str) -> float | None:
    """The calibrated floor of a candidate channel's statistic (see the rule), or None (not calibrated)."""
    nf = _floors()
    if nf is None:
        return None
    v = nf.SCREEN.get(f"{effect}:{channel}")
    return None if v is None else float(v)


def gain_centre(effect: str, channel: str) -> float | None:
    """The mean of a candidate channel's statistic on the clean cases (``CENTRE`` of the calibration), or None
    (not calibrated, or a calibration written before centres were kept): the "no effect" value of a statistic
    without a physical zero (the frames' edge sharpness, :func:`synthaug.diagnose.frame_pattern.sharp_edges`)."""
    nf = _floors()
    if nf is None:
        return None
    v = getattr(nf, "CENTRE", {}).get(f"{effect}:{channel}")
    return None if v is None else float(v)


def gain_upper(effect: str, channel: str) -> float | None:
    """Where a candidate channel's statistic stays on the clean cases (``UPPER`` of the calibration: ``max(μ + zσ,
    max)``, z the one-sided rule's, not clamped at 0 as the floor is), or None (not calibrated, or a calibration
    written before it was kept). A distance gain below it is what clean data give: the objects do not show the
    effect (a sharpening's frame channel asks it of the objects, :func:`~synthaug.diagnose.screening.objects_agree`)."""
    nf = _floors()
    if nf is None:
        return None
    v = getattr(nf, "UPPER", {}).get(f"{effect}:{channel}")
    return None if v is None else float(v)


def rule_text() -> str:
    """The significance rule in one paragraph, for the report."""
    nf = _floors()
    if nf is None:
        return ("Significance: Bonferroni-corrected tests at α, and hand-set floors on the effect size "
                "(no null calibration found).")
    s = nf.SOURCE
    return (f"Significance: a statistic counts when its test rejects 'no effect' at α (Bonferroni) **and** its "
            f"value leaves the range that clean measured data give it — measured on {s['n_cases']} clean "
            f"nuisance-varied reference-camera seed sets of {s['n_seeds']} seeds (material, light, mesh and a "
            f"moving scene drawn at random, nothing hidden): ± {s['z_two_sided']:.2f} σ of the clean values around "
            f"their mean and around 0 (widened to their min/max) for residual measures, μ + {s['z_one_sided']:.2f} σ for a "
            f"candidate's held-out gain (an absorbed parameter's dependence in the direction its effect predicts; "
            f"the other direction counts as no gain), set for a {100 * s['family_rate']:.0f} % false-alarm rate per clean case over "
            f"{s['n_statistics']} statistics (`{s['command']}`, {s['date']}). "
            + (f"The colour channel's chroma gains: μ + {s['colour']['z_one_sided']:.2f} σ over "
               f"{s['colour']['n_cases']} clean colour cases (objects painted near-neutral; "
               f"{s['colour']['n_statistics']} statistics on a colour case; `{s['colour']['command']}`)."
               if s.get("colour") else "Statistics without a clean null (colour) keep hand-set floors."))


def describe() -> dict[str, Any]:
    """Which floors are in use: the calibration's source and values, and the hand-set fallbacks."""
    from synthaug.diagnose.noise import SLOPE_FLOOR

    nf = _floors()
    out: dict[str, Any] = {"hand_floors": dict(HAND_FLOORS), "hand_min_gain": HAND_MIN_GAIN,
                           "hand_noise_slope_floor": SLOPE_FLOOR}
    if nf is None:
        out["source"] = "hand-set"
    else:
        out.update({"source": dict(nf.SOURCE), "structure": dict(nf.STRUCTURE), "screen": dict(nf.SCREEN)})
    return out


# ------------------------------------------------------------------ derivation (the benchmark's side)
def one_sided_floor(values: Sequence[float], z: float) -> float:
    """The rule's floor of a one-sided statistic from its clean values: ``max(max(μ, 0) + zσ, max, 0)`` (μ, σ their
    mean and standard deviation, ddof 1).

    Example:
        >>> round(one_sided_floor([-0.01, 0.01, 0.03], 2.0), 6)  # mean 0.01, sd 0.02
        0.05
        >>> round(one_sided_floor([-0.3, -0.1], 0.5), 4)  # mean below 0: 0 + 0.5 sd
        0.0707
    """
    import numpy as np

    v = np.asarray(values, np.float64)
    mu, sd = float(v.mean()), float(v.std(ddof=1))
    return max(max(mu, 0.0) + z * sd, float(v.max()), 0.0)


def clean_upper(values: Sequence[float], z: float) -> float:
    """Where a statistic's clean values stay: ``max(μ + zσ, max)`` (ddof 1), :func:`one_sided_floor` without its clamp
    at 0 (``UPPER`` of the calibration).

    Example:
        >>> round(clean_upper([-0.3, -0.1], 0.5), 4), round(one_sided_floor([-0.3, -0.1], 0.5), 4)
        (-0.1, 0.0707)
    """
    import numpy as np

    v = np.asarray(values, np.float64)
    return max(float(v.mean()) + z * float(v.std(ddof=1)), float(v.max()))


def derive_floors(stats: Sequence[dict[str, Any]], *, family_rate: float = FAMILY_RATE,
                  min_cases: int = 10, colour_stats: Sequence[dict[str, Any]] | None = None,
                  directions: dict[str, int] | None = None) -> dict[str, Any]:
    """Null ranges and floors from clean cases' statistics (``bench_diagnose_null.case_statistics`` rows).

    Args:
        stats: one dict per clean case: ``{"residual:<measure>": {"value": ...}, "screen:<effect>:<channel>":
            {"gain": ..., "slope": ...}}``.
        family_rate: false-alarm rate per case the floors are set for (Bonferroni over the statistics).
        min_cases: a statistic seen in fewer clean cases is not calibrated (keeps its hand-set floor).
        colour_stats: rows of clean colour cases: their colour channels (``screen:<effect>:distance:colour``)
            only, floored with z for the statistics a colour case holds (those of ``stats`` and these). The
            colour channels of ``stats`` are never used: a gray case has none.
        directions: ``{"effect:absorbed": sign}``, the sign of the dependence each absorbed channel's effect
            predicts (:data:`synthaug.diagnose.screening.ABSORPTION`'s third field, which the benchmark passes):
            a clean value whose ``rho`` has the other sign counts as ``-|gain|``, since the channel's test
            (``sign_ok``) never names its effect from it. Without it, or without ``rho``, the value counts as it is.

    Returns:
        ``{"STRUCTURE": {measure: [lo, hi]}, "SCREEN": {"effect:channel": floor}, "CENTRE": {"effect:channel":
        the clean mean}, "UPPER": {"effect:channel": max(μ + zσ, max), where the clean values stay, without the floor's
        clamp at 0}, "z_two_sided", "z_one_sided", "n_statistics"}``, with ``colour_stats`` also
        ``"colour": {"z_one_sided", "n_statistics"}``.

    Example:
        >>> rows = [{"residual:tone_curve": {"value": v}} for v in (-0.1, 0.0, 0.1, 0.05, -0.05) * 2]
        >>> f = derive_floors(rows, min_cases=5)
        >>> [round(x, 3) for x in f["STRUCTURE"]["tone_curve"]], round(f["z_two_sided"], 3)
        ([-0.146, 0.146], 1.96)
    """
    import numpy as np
    from scipy import stats as st

    from synthaug.diagnose.noise import NOISE_CANDIDATES

    values: dict[str, list[float]] = {}
    for case in stats:
        for key, row in case.items():
            kind = key.split(":")
            if kind[0] == "residual":
                v = row.get("value")
            elif kind[-1] == "noise_level":
                v = None if row.get("slope") is None else row["slope"] * NOISE_CANDIDATES.get(kind[1], 1)
            elif kind[-1] == "colour":
                continue  # colour channels: from colour cases only (colour_stats)
            elif kind[-1] == "absorbed" and f"{kind[1]}:absorbed" in (directions or {}) \
                    and row.get("rho") is not None and row.get("gain") is not None:
                # one-sided, as the channel's test (sign_ok): a dependence of the sign the effect does not predict
                # never names it, so it is no gain (stop 95: one clean case's w_d rising with the frame's
                # brightness, R² 0.243, had set auto-exposure's floor, whose dependence falls)
                g = float(row["gain"])
                v = g if float(row["rho"]) * directions[f"{kind[1]}:absorbed"] > 0 else -abs(g)
            else:
                v = row.get("gain")
            if v is not None and math.isfinite(float(v)):
                values.setdefault(key, []).append(float(v))
    colour: dict[str, list[float]] = {}
    for case in colour_stats or ():
        for key, row in case.items():
            v = row.get("gain")
            if key.endswith(":distance:colour") and v is not None and math.isfinite(float(v)):
                colour.setdefault(key, []).append(float(v))
    keep = {k: np.asarray(v) for k, v in values.items() if len(v) >= min_cases}
    keep_colour = {k: np.asarray(v) for k, v in colour.items() if len(v) >= min_cases}
    n_two = sum(1 for k in keep if k.startswith("residual:"))
    n_stats = max(len(keep), 1)
    z2 = float(st.norm.isf(family_rate / (2 * n_stats)))
    z1 = float(st.norm.isf(family_rate / n_stats))
    structure, screen, centre, upper = {}, {}, {}, {}
    for key, v in sorted(keep.items()):
        # the null family: the measured nuisance mismatch (mean mu) and a model that is exactly right (0),
        # both with the clean cases' spread sd
        mu, sd = float(v.mean()), float(v.std(ddof=1))
        if key.startswith("residual:"):
            structure[key.split(":", 1)[1]] = [min(min(mu, 0.0) - z2 * sd, float(v.min())),
                                               max(max(mu, 0.0) + z2 * sd, float(v.max()))]
        else:
            screen[key.split(":", 1)[1]] = one_sided_floor(v, z1)
            centre[key.split(":", 1)[1]] = mu
            upper[key.split(":", 1)[1]] = clean_upper(v, z1)
    out = {"STRUCTURE": structure, "SCREEN": screen, "CENTRE": centre, "UPPER": upper, "z_two_sided": z2,
           "z_one_sided": z1,
           "n_statistics": n_stats, "n_two_sided": n_two}
    if keep_colour:
        n_colour_case = len(keep) + len(keep_colour)  # the statistics a colour case holds
        z1c = float(st.norm.isf(family_rate / n_colour_case))
        for key, v in sorted(keep_colour.items()):
            screen[key.split(":", 1)[1]] = one_sided_floor(v, z1c)
            centre[key.split(":", 1)[1]] = float(v.mean())
            upper[key.split(":", 1)[1]] = clean_upper(v, z1c)
        out["colour"] = {"z_one_sided": z1c, "n_statistics": n_colour_case}
    return out


def write_floors_module(path: str | Path, stats: Sequence[dict[str, Any]], *, command: str, n_cases: int,
                        n_seeds: int, family_rate: float = FAMILY_RATE,
                        colour_stats: Sequence[dict[str, Any]] | None = None,
                        colour_source: dict[str, Any] | None = None, directions: dict[str, int] | None = None
                        ) -> Path:
    """Write :mod:`synthaug.diagnose.null_floors` (the floors, the command that measured them, its date); with
    ``colour_stats`` (clean colour cases' rows) the colour channels' floors too, ``colour_source`` their
    ``command`` and ``n_cases``."""
    import json
    import pprint

    f = derive_floors(stats, family_rate=family_rate, colour_stats=colour_stats, directions=directions)
    source = {"command": command, "date": _dt.date.today().isoformat(), "n_cases": int(n_cases),
              "n_seeds": int(n_seeds), "family_rate": family_rate, "z_two_sided": round(f["z_two_sided"], 4),
              "z_one_sided": round(f["z_one_sided"], 4), "n_statistics": f["n_statistics"]}
    if "colour" in f:
        source["colour"] = {**(colour_source or {}), "z_one_sided": round(f["colour"]["z_one_sided"], 4),
                            "n_statistics": f["colour"]["n_statistics"]}
    rnd = lambda x: round(float(x), 6)  # noqa: E731
    structure = {k: [rnd(a), rnd(b)] for k, (a, b) in f["STRUCTURE"].items()}
    screen = {k: rnd(v) for k, v in f["SCREEN"].items()}
    centre = {k: rnd(v) for k, v in f["CENTRE"].items()}
    upper = {k: rnd(v) for k, v in f["UPPER"].items()}
    text = (
        '"""Null floors of the diagnosis: GENERATED by benchmarks/bench_diagnose_null.py (see SOURCE); do not edit.\n\n'
        "The rule that uses them: :mod:`synthaug.diagnose.calibration`.\n"
        '"""\n\n'
        f"SOURCE = {pprint.pformat(source, width=110, sort_dicts=True)}\n\n"
        "# residual structure measure -> [lo, hi]: the range of its value on clean nuisance-varied data\n"
        f"STRUCTURE = {pprint.pformat(structure, width=110, sort_dicts=True)}\n\n"
        "# 'effect:channel' -> floor of its held-out gain (absorbed: held-out R2; noise_level: slope in the\n"
        "# candidate's direction; frame: the frames' fall-off k, block-grid log ratio or edge ratio; distance:colour:\n"
        "# the chroma gain, from clean colour cases) on clean nuisance-varied data\n"
        f"SCREEN = {pprint.pformat(screen, width=110, sort_dicts=True)}\n\n"
        "# 'effect:channel' -> the mean of that statistic on the clean cases (the 'no effect' value of a statistic\n"
        "# without a physical zero: the frames' edge sharpness)\n"
        f"CENTRE = {pprint.pformat(centre, width=110, sort_dicts=True)}\n\n"
        "# 'effect:channel' -> max(mean + z sd, max) of that statistic on the clean cases, not clamped at 0: what a\n"
        "# clean case's value stays under (a sharpening the frames show must fit the objects better than that)\n"
        f"UPPER = {pprint.pformat(upper, width=110, sort_dicts=True)}\n"
    )
    json.dumps(source)  # the source must stay JSON-able (the report quotes it)
    path = Path(path)
    path.write_text(text)
    return path
