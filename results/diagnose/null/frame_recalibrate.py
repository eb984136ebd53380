"""Issue 20, stop 67: the frame channels' clean statistics remade with today's code, without refitting.

The four frame channels (:data:`synthaug.diagnose.screening.FRAME_CANDIDATES`: vignetting, compression, sharpening,
lens distortion) read the whole frames and their background frames only (``screening.frame_evidence``), never the
fit. So their clean null distributions can be remade from the calibration's seed sets alone: the same seeds and
nuisances as ``benchmarks/bench_diagnose_null.py`` (made by ``edge_radial.group_cases``; ``:full`` for the full-fit
sets, whose seed sets the bench makes at that fit's view step and sprite size), the frame summaries
exactly as the diagnosis makes them (``diagnosis_data._frame_summaries``), and the diagnosis's own
``frame_evidence`` and ``frame_channel`` with its Bonferroni count. The lens's estimator changed at stop 55 (the
coarse-to-fine Gauss-Newton of ``frame_pattern.radial_flow``) after its floor was calibrated (stop 41); the other
three channels serve as the check that the cases are the calibration's own (their values must come back as stored).

For each ``--calibration`` output (``bench_diagnose_null.py``'s JSON) it compares the stored frame statistics with
the remade ones and, with ``--write-dir``, writes a copy of that output whose four frame null distributions are the
remade ones (every other statistic untouched, a ``frame_refresh`` field saying so). ``bench_diagnose_null.py
--floors-from <copies> --write-floors ...`` then regenerates the floors from them. Groups given with ``--fresh``
are judged only: how many clean cases a frame channel would name under the floors now in
:mod:`synthaug.diagnose.null_floors`.

Usage::

    PYTHONPATH=. python results/diagnose/null/frame_recalibrate.py \\
        --calibration clean:2000:24=results/diagnose/null/calibration_set_hand.json \\
                      clean:4000:20:full=results/diagnose/null/full_fit_calibrated.json \\
        --write-dir results/diagnose/null/frame_refresh --out results/diagnose/null/frame_recalibrate.json
    PYTHONPATH=. python results/diagnose/null/frame_recalibrate.py --fresh clean:3000:24 clean:5000:20:full \\
        --out results/diagnose/null/frame_recalibrate_fresh.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[3]))

from benchmarks.bench_diagnose_null import summarise  # noqa: E402  (null distributions as the bench writes them)
from edge_radial import group_cases, write_out  # noqa: E402  (the calibration's cases and sizes)


class _FrameData:
    """What ``screening.frame_evidence`` reads of a :class:`~synthaug.diagnose.diagnosis_data.DiagnosisData`: the
    frame summaries and the seeds' records (their videos are the scenes)."""

    def __init__(self, summaries: list[dict[str, Any]], records: list[dict[str, Any]]):
        self.frame_summaries, self.records = summaries, records

    def __len__(self) -> int:
        return len(self.records)


def case_channels(seeds, geo) -> dict[str, dict[str, Any]]:
    """The case's four frame channels as the diagnosis screens them (gray data, every candidate asked)."""
    from synthaug.diagnose.diagnosis_data import _frame_summaries, _read_frames
    from synthaug.diagnose.screening import (CANDIDATE_GRIDS, FRAME_CANDIDATES, frame_channel, frame_evidence,
                                             n_screening_tests)

    data = _FrameData(_frame_summaries(seeds, _read_frames(seeds), geo, seeds.patch_size), list(seeds.records))
    n_tests = n_screening_tests(list(CANDIDATE_GRIDS))  # every candidate asked: report.py's count
    ev = frame_evidence(data)
    out = {}
    for effect in FRAME_CANDIDATES:
        ch = frame_channel(effect, ev, n_tests, 0.01)
        if ch is not None and ch.get("gain") is not None and np.isfinite(ch["gain"]):
            out[f"screen:{effect}:frame"] = {"gain": float(ch["gain"]), "p_adjusted": float(ch["p_adjusted"]),
                                             "z": ch["z"], "significant": bool(ch["significant"])}
    return out


def run_group(group: str, workdir: str) -> list[dict[str, Any]]:
    rows = []
    for k, seeds, geo in group_cases(group, workdir):
        rows.append(case_channels(seeds, geo))
        print(group, k, {n.split(":")[1]: round(v["gain"], 6) for n, v in rows[-1].items()}, flush=True)
    return rows


def compare(stored: dict[str, Any], remade: dict[str, Any]) -> dict[str, Any]:
    """Stored against remade values of each frame statistic (in case order, the cases with a value)."""
    out = {}
    for name in sorted(set(stored) | set(remade)):
        a = (stored.get(name) or {}).get("gain", {}).get("values", [])
        b = (remade.get(name) or {}).get("gain", {}).get("values", [])
        row: dict[str, Any] = {"n_stored": len(a), "n_remade": len(b)}
        if len(a) == len(b) and a:
            d = np.abs(np.asarray(a) - np.asarray(b))
            row.update(max_abs_diff=float(d.max()), stored_max=float(max(a)), remade_max=float(max(b)))
        out[name] = row
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--calibration", nargs="*", default=[], metavar="GROUP=JSON",
                    help="a calibration group and the bench output it made, e.g. clean:2000:24=calibration.json")
    ap.add_argument("--fresh", nargs="*", default=[], metavar="GROUP", help="clean groups to judge only")
    ap.add_argument("--workdir", default="outputs/edge_radial", help="where the cases' seed sets are (made once)")
    ap.add_argument("--write-dir", default=None, help="write the refreshed copies of the calibration outputs here")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    from synthaug.diagnose import null_floors
    from synthaug.diagnose.calibration import one_sided_floor
    from synthaug.diagnose.screening import FRAME_CANDIDATES

    t0 = time.perf_counter()
    out: dict[str, Any] = {"command": " ".join(["python"] + sys.argv), "floors_in_use": dict(null_floors.SOURCE),
                           "calibration": {}, "fresh": {}}
    pooled: dict[str, list[float]] = {}
    for spec in a.calibration:
        group, path = spec.split("=", 1)
        rows = run_group(group, a.workdir)
        remade = summarise(rows)
        d = json.loads(Path(path).read_text())
        stored = {k: v for k, v in d["null_distributions"].items() if k.endswith(":frame")}
        out["calibration"][group] = {"source": path, "compare": compare(stored, remade), "remade": remade}
        for name, entry in remade.items():
            pooled.setdefault(name, []).extend(entry["gain"]["values"])
        if a.write_dir:
            d["null_distributions"] = {**{k: v for k, v in d["null_distributions"].items()
                                          if not k.endswith(":frame")}, **remade}
            d["frame_refresh"] = {"by": out["command"], "statistics": sorted(remade),
                                  "note": "the frame channels' null distributions remade with this commit's code from "
                                          "the same seed sets (they never read the fit); every other statistic as "
                                          "measured by the command above"}
            dest = Path(a.write_dir) / Path(path).name
            dest.parent.mkdir(parents=True, exist_ok=True)
            dest.write_text(json.dumps(d, indent=1))
            out["calibration"][group]["wrote"] = str(dest)
    if pooled:
        z = float(null_floors.SOURCE["z_one_sided"])
        out["floors"] = {f"{e}:frame": {"old": null_floors.SCREEN.get(f"{e}:frame"),
                                        "new": one_sided_floor(pooled[f"screen:{e}:frame"], z),
                                        "cases": len(pooled[f"screen:{e}:frame"])}
                         for e in FRAME_CANDIDATES if f"screen:{e}:frame" in pooled}
        print("floors", out["floors"], flush=True)
    for group in a.fresh:
        rows = run_group(group, a.workdir)
        out["fresh"][group] = {"cases": len(rows), "named": {
            name: sum(1 for r in rows if r.get(name, {}).get("significant")) for name in sorted({n for r in rows
                                                                                            for n in r})},
            "remade": summarise(rows)}
        print(group, out["fresh"][group]["named"], flush=True)
    return write_out(out, a.out, t0)


if __name__ == "__main__":
    sys.exit(main())
