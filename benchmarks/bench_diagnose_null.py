"""Null calibration of the diagnosis (issue 20, item 3): clean, nuisance-varied measured data, one command.

Makes ``--cases`` clean measured seed sets (nothing hidden) from the reference camera, each with its own
nuisances drawn at random (:meth:`synthaug.diagnose.nuisances.Nuisances.draw`: material, light per video,
real mesh, a scene that moves between frame and background), fits each, runs ``diagnose`` on each, and
prints JSON: the false-alarm rate (a clean case with any finding) with its Wilson 95 % interval, the
findings per case, and the null distribution of every statistic that can raise a finding (residual
structure measures; each candidate's screening channels). Everything is a pure function of the seeds.

Usage::

    python benchmarks/bench_diagnose_null.py --cases 24 --out results/diagnose/null/null.json
    # derive the significance floors from the null distributions (writes synthaug/diagnose/null_floors.py):
    python benchmarks/bench_diagnose_null.py --cases 24 --write-floors synthaug/diagnose/null_floors.py

Case ``k`` uses reference-camera seed ``--base-seed + k`` and nuisances ``Nuisances.draw(default_rng([base,
k]))``. Sizes follow the diagnosis tests (``tests/test_diagnose.py``: 192x256 frames, objects 20-32 px, w_d
0.3-0.45 per video) at ``--seeds 60``; ``--fit converged`` is the tests' fit (per-seed CMA-ES, budget 250,
from the true pose; view grid 20 deg, sprites 48 px), ``--fit full`` the demo's ``synthaug fit`` (random
start, ``--budget``, ``--step-deg``, ``--sprite-size``). Seed sets and fits are kept in ``--workdir`` and
reused (the diagnosis is always rerun), so calibrations before and after a change of rules see the same data.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time
from pathlib import Path
from typing import Any


CONVERGED_VIEWS = (20.0, 48)  # (view step in degrees, sprite px) of a case's seed set for the tests' converged fit
FULL_FIT_VIEWS = (10.0, 64)  # ... and, by default (--step-deg, --sprite-size), for synthaug fit's full fit


def case_seedset(dest: Path, k: int, *, base_seed: int, n_seeds: int, nuisances: Any, hidden: str | None = None,
                 strength: str = "default", colour: bool = False,
                 views: tuple[float, int] = CONVERGED_VIEWS) -> None:
    """Case ``k``'s measured seed set at ``dest``: the reference camera's frames (192x256, objects 20-32 px) of
    ``n_seeds`` seeds drawn from ``base_seed + k``, with ``nuisances`` and the hidden effect's setting; its views and
    sprites at ``views``, those of the fit the case is made for. The one home of a case's seed set: the scripts that
    read cases' frames without a fit (``results/diagnose/null/edge_radial.py``) make them here too."""
    from synthaug.diagnose.reference_camera import make_measured_seedset

    make_measured_seedset(dest, n_seeds=n_seeds, hidden=hidden_settings(hidden, strength) if hidden else None,
                          nuisances=nuisances, colour=colour, frame_size=(192, 256), object_px=(20.0, 32.0),
                          view_step_deg=views[0], sprite_size=views[1], seed=base_seed + k,
                          paper_ranges={"w_d": (0.3, 0.45)})


def wilson(k: int, n: int) -> tuple[float, float]:
    """Wilson score 95 % interval of k / n (the library's :func:`synthaug.diagnose.gap.binomial_ci`)."""
    from synthaug.diagnose.gap import binomial_ci

    return binomial_ci(k, n, method="wilson")


def hidden_settings(effect: str, strength: str) -> dict[str, dict[str, Any]]:
    """The hidden effect's settings: ``"default"`` its realistic default (REALISTIC_STRENGTHS); ``"alt"`` a second
    realistic strength, each setting at the end of its realistic range farther from the default (the high end on a
    tie; a per-seed pair becomes the whole range)."""
    from synthaug.diagnose.reference_camera.settings import REALISTIC_RANGES, REALISTIC_STRENGTHS

    base = dict(REALISTIC_STRENGTHS[effect])
    if strength == "default":
        return {effect: base}
    alt: dict[str, Any] = {}
    for name, value in base.items():
        lo, hi = REALISTIC_RANGES[effect][name]
        alt[name] = (lo, hi) if isinstance(value, tuple) else (lo if abs(value - lo) > abs(hi - value) else hi)
    return {effect: alt}


def make_case(work: Path, k: int, a: argparse.Namespace) -> tuple[Path, Path, dict[str, Any], float]:
    import numpy as np

    from synthaug.diagnose.nuisances import Nuisances

    case = work / f"case_{k:03d}"
    seeds, fit = case / "seeds", case / "fit.json"
    nz = Nuisances.none() if a.no_nuisances else Nuisances.draw(np.random.default_rng([a.base_seed, k]))
    key = {"k": k, "base_seed": a.base_seed, "seeds": a.seeds, "fit": a.fit, "budget": a.budget,
           "step_deg": a.step_deg, "sprite_size": a.sprite_size, "nuisances": nz.as_dict(),
           **({"hidden": a.hidden} if a.hidden else {}), **({"colour": True} if a.colour else {}),
           **({"strength": a.strength} if a.strength != "default" else {})}
    stamp = case / "case.json"
    if stamp.exists() and json.loads(stamp.read_text()).get("key") == key and fit.exists():
        return seeds, fit, json.loads(stamp.read_text()), 0.0
    t = time.perf_counter()
    case_seedset(seeds, k, base_seed=a.base_seed, n_seeds=a.seeds, nuisances=nz, hidden=a.hidden, strength=a.strength,
                 colour=a.colour, views=CONVERGED_VIEWS if a.fit == "converged" else (a.step_deg, a.sprite_size))
    if a.fit == "converged":
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
        from test_diagnose import converged_fit  # the diagnosis tests' fit (per-seed CMA-ES from the truth)

        converged_fit(seeds, fit)
    else:
        from synthaug.fit.fitting import FitConfig, fit_seedset

        fit_seedset(seeds, "quadcopter", fit, FitConfig(distance="hog", budget=a.budget, seed=k,
                                                        step_deg=a.step_deg, sprite_size=a.sprite_size), workers=1)
    prep = time.perf_counter() - t
    info = {"key": key, "prep_seconds": prep}
    stamp.write_text(json.dumps(info, indent=1))
    return seeds, fit, info, prep


# The residual structure that names each effect outside the candidate list (reference_camera.OUTSIDE_EFFECTS)
OUTSIDE_STRUCTURE = {"interlacing": "periodic_rows", "column_pattern": "column_pattern"}


def explained_better(report: dict[str, Any]) -> list[str]:
    """The significant distance gains of ``report``'s screening that named nothing because another candidate
    explained the same distance better (:func:`synthaug.diagnose.screening.explained_better`), as
    ``"defocus (distance:pixel) < haze"``: which cases the rule touched, without rerunning them."""
    return [f"{r['effect']} ({c['channel']}) < {c['explained_better_by']['effect']}"
            for r in report.get("screened") or [] for c in r.get("channels") or [] if c.get("explained_better_by")]


def _first_name(findings: list[str], hidden: str | None) -> str | None:
    """The name a case's findings give first: the first finding's effect; for an effect outside the candidates,
    the effect itself when an "unexplained" finding lists its structure (a candidate named before it is not a
    misnaming then: it may explain a part, as a blur explains part of interlacing's comb)."""
    if not findings:
        return None
    if hidden in OUTSIDE_STRUCTURE:
        for f in findings:
            if f.startswith("unexplained: ") and OUTSIDE_STRUCTURE[hidden] in f[len("unexplained: "):].split(", "):
                return hidden
        return "unexplained" if findings[0].startswith("unexplained") else findings[0].split(" ")[0]
    return findings[0].split(" ")[0]


def case_statistics(report: dict[str, Any]) -> dict[str, Any]:
    """The statistics of one report that can raise a finding, flat: ``{name: {value, p, significant}}``."""
    out: dict[str, Any] = {}
    for name, m in report["residuals"].items():
        if m.get("skipped") or name == "colour":
            continue
        out[f"residual:{name}"] = {"value": m["value"], "p": m["p"], "significant": m["significant"]}
    for row in report["screened"]:
        for ch in row.get("channels") or []:
            key = f"screen:{row['effect']}:{ch['channel']}"
            v = {"gain": ch.get("gain"), "p_adjusted": ch.get("p_adjusted"), "z": ch.get("z"),
                 "significant": ch.get("significant")}
            for extra in ("raw_gain_all", "rho", "slope"):
                if extra in ch:
                    v[extra] = ch[extra]
            out[key] = v
    return out


def summarise(stats: list[dict[str, Any]]) -> dict[str, Any]:
    """Per statistic over cases: n, mean, sd, quantiles of its value (residual: value; screening: gain and
    raw_gain_all), and how often it was significant."""
    import numpy as np

    names = sorted({k for s in stats for k in s})
    out = {}
    for name in names:
        rows = [s[name] for s in stats if name in s]
        entry: dict[str, Any] = {"n": len(rows), "significant": int(sum(bool(r.get("significant")) for r in rows))}
        for field in ("value", "gain", "raw_gain_all", "rho", "slope", "p", "p_adjusted"):
            vals = np.array([r[field] for r in rows if r.get(field) is not None], np.float64)
            vals = vals[np.isfinite(vals)]
            if len(vals) == 0:
                continue
            entry[field] = {"mean": float(vals.mean()), "sd": float(vals.std(ddof=1)) if len(vals) > 1 else 0.0,
                            "min": float(vals.min()), "q05": float(np.quantile(vals, 0.05)),
                            "median": float(np.median(vals)), "q95": float(np.quantile(vals, 0.95)),
                            "max": float(vals.max()), "values": [round(float(v), 6) for v in vals]}
        out[name] = entry
    return out


def parser() -> argparse.ArgumentParser:
    """The command line (also read back from a recorded ``command`` to make its cases again)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", type=int, default=24)
    ap.add_argument("--seeds", type=int, default=60)
    ap.add_argument("--base-seed", type=int, default=2000)
    ap.add_argument("--fit", choices=("converged", "full"), default="converged")
    ap.add_argument("--budget", type=int, default=800)
    ap.add_argument("--step-deg", type=float, default=FULL_FIT_VIEWS[0])
    ap.add_argument("--sprite-size", type=int, default=FULL_FIT_VIEWS[1])
    ap.add_argument("--no-nuisances", action="store_true", help="the fit's own model (the old reference camera)")
    ap.add_argument("--strength", choices=["default", "alt"], default="default",
                    help="with --hidden: the realistic default setting, or a second realistic strength (each setting "
                         "at the end of its realistic range farther from the default)")
    ap.add_argument("--colour", action="store_true",
                    help="colour cases (RGB reference camera): the colour effects (white balance, chromatic "
                         "aberration, haze's airlight) are only identifiable there")
    ap.add_argument("--hidden", default=None, metavar="EFFECT",
                    help="not a null run: hide this effect (realistic strength) in every case and report how often "
                         "it is named first and significant (the power at these floors)")
    ap.add_argument("--workdir", default="outputs/bench_diagnose_null")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--rules", choices=("calibrated", "hand"), default="calibrated",
                    help="significance floors: the calibrated ones (synthaug/diagnose/null_floors.py, when present) "
                         "or the hand-set ones they replaced")
    ap.add_argument("--out", default=None, help="also write the JSON here")
    ap.add_argument("--write-floors", default=None, metavar="PY",
                    help="derive the significance floors from these null distributions and write them as a module")
    ap.add_argument("--floors-from", nargs="+", default=None, metavar="JSON",
                    help="no new cases: pool the null distributions of these earlier outputs (e.g. the tests' fit "
                         "and the demo's fit) and write --write-floors from them")
    ap.add_argument("--colour-floors-from", nargs="+", default=[], metavar="JSON",
                    help="with --floors-from: clean colour cases' outputs (--colour, nothing hidden) whose colour "
                         "channels (distance:colour) are floored too")
    return ap


def main() -> int:
    ap = parser()
    a = ap.parse_args()
    if a.colour_floors_from and not a.floors_from:
        ap.error("--colour-floors-from needs --floors-from (the gray floors are written with them)")
    if a.floors_from:
        if not a.write_floors:
            ap.error("--floors-from needs --write-floors")
        return pool_floors(a)
    if a.cases < 1 or a.seeds < 10:
        ap.error(f"need --cases >= 1 and --seeds >= 10, got {a.cases} and {a.seeds}")
    import torch

    torch.set_num_threads(a.threads)
    from synthaug.diagnose import calibration
    from synthaug.diagnose.report import diagnose

    work = Path(a.workdir)
    work.mkdir(parents=True, exist_ok=True)
    t_all = time.perf_counter()
    cases, stats, prep_s, diag_s = [], [], [], []
    for k in range(a.cases):
        seeds, fit, info, prep = make_case(work, k, a)
        t = time.perf_counter()
        with (calibration.hand_set() if a.rules == "hand" else contextlib.nullcontext()):
            rep = diagnose(seeds, "quadcopter", fit, out_dir=None, plots=False, seed=0)
        diag_s.append(time.perf_counter() - t)
        prep_s.append(prep)
        st = case_statistics(rep)
        stats.append(st)
        found = [f"{f['effect']} ({f['channel']})" if f["effect"] != "unexplained"
                 else "unexplained: " + ", ".join(f["structure"]) for f in rep["findings"]]
        cases.append({"case": k, "findings": found, "diagnosis_seconds": diag_s[-1],
                      "settings": [f.get("setting") for f in rep["findings"] if f["effect"] != "unexplained"],
                      "explained_better": explained_better(rep), "nuisances": info["key"]["nuisances"]})
        print(f"case {k}: {found or 'nothing'} ({diag_s[-1]:.0f} s diagnosis, {prep:.0f} s data+fit)",
              file=sys.stderr, flush=True)
    n_alarm = sum(bool(c["findings"]) for c in cases)
    lo, hi = wilson(n_alarm, len(cases))
    power = None
    if a.hidden:
        first = [_first_name(c["findings"], a.hidden) for c in cases]
        named = sum(f == a.hidden for f in first)
        wrong = sum(f is not None and f != a.hidden for f in first)
        power = {"hidden": a.hidden, "named_first": named, "misnamed_first": wrong, "missed": first.count(None),
                 "named_first_rate": named / len(cases), "wilson95": list(wilson(named, len(cases))),
                 "settings_named_first": [c["settings"][0] for c, f in zip(cases, first)
                                          if f == a.hidden and c["settings"]],
                 **({"rule": f"an effect outside the candidates counts as named when an 'unexplained' finding "
                             f"lists its structure ({OUTSIDE_STRUCTURE[a.hidden]})"}
                    if a.hidden in OUTSIDE_STRUCTURE else {})}

    result = {
        "bench": "diagnose_null", "command": " ".join(["python"] + sys.argv), "cases": len(cases),
        "seeds": a.seeds, "fit": a.fit, "nuisances": not a.no_nuisances, "colour": bool(a.colour), "base_seed": a.base_seed,
        "strength": a.strength, "hidden_settings": hidden_settings(a.hidden, a.strength) if a.hidden else None,
        "rules": a.rules,
        "floors_in_use": (calibration.describe() if a.rules == "calibrated" else {"source": "hand-set"}),
        "hidden": a.hidden, "power": power,
        "false_alarm_rate": None if a.hidden else n_alarm / len(cases), "false_alarms": None if a.hidden else n_alarm,
        "wilson95": None if a.hidden else [lo, hi],
        "by_finding": _count([f for c in cases for f in c["findings"]]),
        "wall_seconds": time.perf_counter() - t_all, "diagnosis_seconds_median": sorted(diag_s)[len(diag_s) // 2],
        "diagnosis_seconds_max": max(diag_s), "prep_seconds_total": sum(prep_s),
        "per_case": cases, "null_distributions": summarise(stats),
    }
    text = json.dumps(result, indent=1)
    if a.out:
        Path(a.out).parent.mkdir(parents=True, exist_ok=True)
        Path(a.out).write_text(text)
    if a.write_floors:
        calibration.write_floors_module(a.write_floors, stats, command=result["command"], n_cases=len(cases),
                                        n_seeds=a.seeds, directions=absorbed_directions())
    print(json.dumps({k: v for k, v in result.items() if k not in ("per_case", "null_distributions")}))
    return 0


def absorbed_directions() -> dict[str, int]:
    """The sign of the dependence each absorbed channel's effect predicts (``screening.ABSORPTION``), keyed as the
    floors are: what ``calibration.derive_floors`` counts a clean absorbed value by."""
    from synthaug.diagnose.screening import ABSORPTION

    return {f"{effect}:absorbed": sign for effect, (_, _, sign) in ABSORPTION.items()}


def stats_from_output(path: str | Path) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Per-statistic null values of an earlier output as rows for ``calibration.derive_floors`` (which pools
    values per statistic; the rows need not line up with cases)."""
    d = json.loads(Path(path).read_text())
    rows: list[dict[str, Any]] = []
    for name, entry in d["null_distributions"].items():
        fields = ("value",) if name.startswith("residual:") else ("slope",) if name.endswith("noise_level") \
            else ("gain", "rho") if name.endswith(":absorbed") else ("gain",)  # rho: the dependence's sign
        lengths = {len((entry.get(f) or {}).get("values", [])) for f in fields}
        if len(lengths) > 1:
            raise ValueError(f"{path}: {name}'s {' and '.join(fields)} values do not pair up ({sorted(lengths)})")
        for field in fields:
            for i, v in enumerate((entry.get(field) or {}).get("values", [])):
                while len(rows) <= i:
                    rows.append({})
                rows[i].setdefault(name, {})[field] = v
    return rows, d


def pool_floors(a: argparse.Namespace) -> int:
    from synthaug.diagnose import calibration

    rows, n_cases, seeds, sources = [], 0, set(), []
    for path in a.floors_from:
        r, d = stats_from_output(path)
        if "slope" not in json.dumps(d["null_distributions"].get("screen:gamma:noise_level", {})):
            print(f"{path}: no noise-level slopes recorded", file=sys.stderr)
        rows += r
        n_cases += d["cases"]
        seeds.add(d["seeds"])
        refresh = d.get("frame_refresh")  # frame_recalibrate.py's copy: its frame statistics remade without a refit
        remade = d.get("structure_refresh")  # periodic_s96/recalibrate.py's copy: periodic measures remade
        highlight = d.get("highlight_refresh")  # highlight_s110/recalibrate.py's copy: the highlight statistic added
        sources.append(f"{d['command']} [{d['fit']} fit, {d['cases']} cases"
                       + (f"; frame statistics remade by {refresh['by']}" if refresh else "")
                       + (f"; {', '.join(remade['statistics'])} remade by {remade['by']}" if remade else "")
                       + (f"; screen:specular:highlight added by {highlight['by']}" if highlight else "") + "]")
    colour_rows, colour_cases, colour_sources = [], 0, []
    for path in getattr(a, "colour_floors_from", None) or []:
        r, d = stats_from_output(path)
        if not d.get("colour") or d.get("hidden"):
            raise SystemExit(f"{path}: not a clean colour run (--colour, nothing hidden)")
        colour_rows += r
        colour_cases += d["cases"]
        colour_sources.append(f"{d['command']} [{d['fit']} fit, {d['cases']} cases]")
    command = " ".join(["python"] + sys.argv) + " <- " + " + ".join(sources)
    calibration.write_floors_module(
        a.write_floors, rows, command=command, n_cases=n_cases, n_seeds=max(seeds), colour_stats=colour_rows or None,
        colour_source={"command": " + ".join(colour_sources), "n_cases": colour_cases} if colour_rows else None,
        directions=absorbed_directions())
    print(json.dumps({"wrote": a.write_floors, "cases": n_cases, "from": a.floors_from}))
    return 0


def _count(items: list[str]) -> dict[str, int]:
    out: dict[str, int] = {}
    for x in items:
        out[x] = out.get(x, 0) + 1
    return out


if __name__ == "__main__":
    sys.exit(main())
