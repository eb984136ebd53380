"""Issue 20, stop 96: the ``periodic_*`` structure measures' clean null distributions remade with today's code.

Stop 96 moved the frequency band in which ``residuals.periodic_peak`` seeks the row/column spectra's peak from 0.1
to ``residuals.PERIODIC_MIN_FREQUENCY`` (0.25 cycles per frame px). The measures read the base render of the fit,
so their null values are remade from the calibration's cases themselves (the bench's work folders: seed sets and
fits, made again by the bench's ``--workdir`` cache where absent), with the diagnosis's own ``structure_measures``.
The value the band before the change gives (``periodic_peak(min_frequency=0.1)``) is recorded beside each, to
compare with the stored calibration (remade fits need not be bit-identical to the stored ones).

For each ``--calibration GROUP=JSON=WORKDIR`` it writes, with ``--write-dir``, a copy of the calibration output
whose two ``residual:periodic_*`` null distributions are the remade ones (every other statistic untouched, a
``structure_refresh`` field saying so); ``bench_diagnose_null.py --floors-from <copies> --write-floors ...`` then
regenerates the floors. ``--fresh NAME=WORKDIR`` groups are measured only (their values under both bands).

Usage::

    PYTHONPATH=. python results/diagnose/null/periodic_s96/recalibrate.py --calibration \\
        clean2000=results/diagnose/null/frame_refresh/calibration_set_hand.json=outputs/bench_diagnose_null_hand2000 \\
        full4000=results/diagnose/null/frame_refresh/full_fit_calibrated.json=outputs/bench_diagnose_null_full \\
        --write-dir results/diagnose/null/periodic_s96/calibration \\
        --out results/diagnose/null/periodic_s96/recalibrate.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from benchmarks.bench_diagnose_null import summarise  # noqa: E402  (null distributions as the bench writes them)

NAMES = ("periodic_rows", "periodic_columns")


def residual_spectra(case: Path) -> tuple[Any, Any, np.ndarray, np.ndarray, np.ndarray]:
    """A cached case's seeds and base render, and its object residual's row and column spectra (per seed; not
    divided by the object's weight, whose norm cancels in their ratio) with the seeds' frame scale."""
    from synthaug.diagnose.diagnosis_data import load_diagnosis_data
    from synthaug.diagnose.residuals import _line_spectrum, region_masks
    from synthaug.diagnose.screening import base_render

    data = load_diagnosis_data(Path(case) / "seeds", Path(case) / "fit.json", "quadcopter")
    syn, _ = base_render(data)
    m = region_masks(data.coverage)
    wobj = (m["interior"] | m["boundary"]).float()
    res = data.real - syn
    return data, syn, _line_spectrum(res, wobj, -2), _line_spectrum(res, wobj, -1), data.frame_scale.double().numpy()


def case_values(case: Path) -> dict[str, dict[str, Any]]:
    """The case's two periodic measures as the diagnosis measures them, and their value over the old band."""
    from synthaug.diagnose.residuals import periodic_peak, structure_measures

    data, syn, rows, cols, fs = residual_spectra(case)
    s = structure_measures(data, syn, rng=np.random.default_rng(0))
    out = {}
    for name, a, b in (("periodic_rows", rows, cols), ("periodic_columns", cols, rows)):
        f_old, lr_old, _ = periodic_peak(a, b, fs, min_frequency=0.1)
        out[f"residual:{name}"] = {"value": s[name]["value"], "p": s[name]["p"],
                                   "significant": bool(s[name]["significant"]), "frequency": s[name]["frequency"],
                                   "value_band_0.1": float(np.nanmean(lr_old)), "frequency_band_0.1": f_old}
    return out


def run_group(name: str, workdir: str) -> list[dict[str, Any]]:
    rows = []
    for case in sorted(Path(workdir).glob("case_*")):
        rows.append(case_values(case))
        print(name, case.name, {k.split(":")[1]: (round(v["value"], 3), round(v["value_band_0.1"], 3))
                                for k, v in rows[-1].items()}, flush=True)
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--calibration", nargs="*", default=[], metavar="GROUP=JSON=WORKDIR")
    ap.add_argument("--fresh", nargs="*", default=[], metavar="GROUP=WORKDIR")
    ap.add_argument("--write-dir", default=None)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    t0 = time.perf_counter()
    out: dict[str, Any] = {"command": " ".join(["python"] + sys.argv), "calibration": {}, "fresh": {}}
    for spec in a.calibration:
        group, path, workdir = spec.split("=", 2)
        rows = run_group(group, workdir)
        d = json.loads(Path(path).read_text())
        stored = {k: d["null_distributions"][k]["value"]["values"] for k in (f"residual:{n}" for n in NAMES)}
        remade = summarise([{k: {"value": v["value"], "p": v["p"], "significant": v["significant"]}
                             for k, v in r.items()} for r in rows])
        out["calibration"][group] = {"source": path, "workdir": workdir, "cases": rows, "stored_values": stored,
                                     "remade": remade}
        if a.write_dir:
            d["null_distributions"] = {**d["null_distributions"], **remade}
            d["structure_refresh"] = {"by": out["command"], "statistics": sorted(remade),
                                      "note": "the periodic_* measures' null distributions remade with this commit's "
                                              "code from the cases of the work folder named; every other statistic as "
                                              "measured before"}
            dest = Path(a.write_dir) / Path(path).name
            dest.parent.mkdir(parents=True, exist_ok=True)
            dest.write_text(json.dumps(d, indent=1))
            out["calibration"][group]["wrote"] = str(dest)
    for spec in a.fresh:
        group, workdir = spec.split("=", 1)
        out["fresh"][group] = {"workdir": workdir, "cases": run_group(group, workdir)}
    out["wall_seconds"] = round(time.perf_counter() - t0, 1)
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
