"""Issue 20, stop 66: the frames' edge-sharpness trend toward the corners as the diagnosis reads it
(:func:`synthaug.diagnose.frame_pattern.sharp_edges`' ``radial``: each frame's :func:`~synthaug.diagnose.frame_pattern.
edge_radial` from :func:`~synthaug.diagnose.frame_pattern.frame_summary`, averaged over scenes), on the calibration's
clean cases and the power table's cases (the same seeds, nuisances and hidden settings as
``benchmarks/bench_diagnose_null.py``; only the seed sets are made, the frame statistics do not read the fit), and the
floor the calibration's rule gives it on the clean cases: ``max(max(mu, 0) + z sigma, max)`` with the calibration's
one-sided z (:mod:`synthaug.diagnose.null_floors`).

Usage::

    PYTHONPATH=. python results/diagnose/null/edge_radial_scenes.py \\
        --out results/diagnose/null/edge_radial_scenes.json lens_distortion:alt:8000:5 clean:2000:24 \\
        clean:4000:20:full sharpening:default:8000:5 sharpening:alt:8000:5

(``:full``: the full-fit calibration set's seed sets, made at that fit's view step and sprite size as the calibration
made them; stop 66 made them at the converged fit's, which moved the floor from 0.045629 to 0.045526.)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edge_radial import groups_parser, run_groups, write_out  # noqa: E402  (stop 45's case maker)


def case_row(seeds, geo) -> dict:
    """The case's frame summaries exactly as the diagnosis makes them (``diagnosis_data._frame_summaries``) and
    :func:`~synthaug.diagnose.frame_pattern.sharp_edges` over them with the diagnosis's groups (the seeds' videos)."""
    from synthaug.diagnose.diagnosis_data import _frame_summaries, _read_frames
    from synthaug.diagnose.frame_pattern import sharp_edges

    summaries = _frame_summaries(seeds, _read_frames(seeds), geo, seeds.patch_size)
    groups = [r.get("video") for r in seeds.records]
    sh = sharp_edges(summaries, groups, centre=None)
    return {"ratio": None if sh is None else sh["ratio"], "radial": None if sh is None else sh["radial"],
            "scenes": None if sh is None else sh["scenes"]}


def main() -> int:
    from synthaug.diagnose import null_floors
    from synthaug.diagnose.calibration import one_sided_floor

    a = groups_parser().parse_args()
    t0 = time.perf_counter()
    out = run_groups(a.groups, a.workdir, case_row)
    clean = [r["radial"] for g, rows in out["groups"].items() if g.startswith("clean") for r in rows
             if r["radial"] is not None and np.isfinite(r["radial"])]
    if len(clean) >= 3:
        z = float(null_floors.SOURCE["z_one_sided"])
        out["clean"] = {"cases": len(clean), "mean": float(np.mean(clean)), "sd": float(np.std(clean, ddof=1)),
                        "max": float(np.max(clean)), "z_one_sided": z, "floor": one_sided_floor(clean, z)}
        print("clean", out["clean"], flush=True)
    return write_out(out, a.out, t0)


if __name__ == "__main__":
    sys.exit(main())
