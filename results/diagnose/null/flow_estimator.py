"""Issue 20: the lens's frame statistic (``radial_flow``'s k over scenes, ``lens_flow``) from the committed estimator
of an earlier revision against the working tree's, on the calibration's clean cases and the power table's lens cases.

``radial_flow`` became a coarse-to-fine Gauss-Newton with the map's exact derivative and the points inside the frame
held fixed on the fine steps (stop 55): about half the time a frame. Its floor (``|k|`` 0.0246, the largest of the 44
clean cases) was calibrated on the earlier estimator; this measures how far each case's statistic moves. Only the
seed sets are made (the frame statistics do not read the fit): the same seeds, nuisances and hidden settings as
``benchmarks/bench_diagnose_null.py`` (``edge_radial.case_frames``).

Usage::

    PYTHONPATH=. python results/diagnose/null/flow_estimator.py --old-rev b845a43 \\
        --out results/diagnose/null/flow_estimator.json clean:2000:24 clean:4000:20 lens_distortion:default:8000:5 \\
        lens_distortion:alt:8000:5
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from edge_radial import group_cases  # noqa: E402

from synthaug.diagnose import frame_pattern as new  # noqa: E402


def module_at(rev: str):
    """``synthaug.diagnose.frame_pattern`` as committed at ``rev``."""
    src = subprocess.run(["git", "show", f"{rev}:synthaug/diagnose/frame_pattern.py"], check=True,
                         capture_output=True, text=True).stdout
    path = Path(tempfile.mkdtemp()) / "frame_pattern_old.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("frame_pattern_old", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("groups", nargs="+", help="clean:BASE:N or EFFECT:STRENGTH:BASE:N")
    ap.add_argument("--old-rev", required=True)
    ap.add_argument("--workdir", default="outputs/edge_radial")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()

    old = module_at(a.old_rev)
    out = {}
    for group in a.groups:
        rows = []
        for k, seeds, geo in group_cases(group, a.workdir):
            p = seeds.patch_size
            recs = seeds.records
            groups = [r.get("video") for r in recs] if len(recs) == len(seeds) else [None] * len(seeds)
            row = {"k": k}
            for name, mod in (("old", old), ("new", new)):
                summaries, t0 = [], time.perf_counter()
                for i in range(len(seeds)):
                    f, bg = np.asarray(seeds.frame(i)), np.asarray(seeds.background_frame(i))
                    exclude = (float(geo["origin"][i, 0]), float(geo["origin"][i, 1]), p * float(geo["frame_scale"][i]))
                    summaries.append(mod.frame_summary(f, background=bg, exclude=exclude))
                lens = mod.lens_flow(summaries, groups)
                row[name] = {"seconds": round(time.perf_counter() - t0, 2),
                             "frames_read": int(sum(np.isfinite(s["flow_k"]) for s in summaries)),
                             "k": None if lens is None else lens["k"], "p": None if lens is None else lens["p"]}
            rows.append(row)
            print(group, json.dumps(row), flush=True)
        out[group] = rows
    if a.out:
        Path(a.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
