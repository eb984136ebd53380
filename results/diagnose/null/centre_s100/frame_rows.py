"""Issue 20, stop 100: the lens's frame channel (``screening.frame_channel``, the diagnosis's own code and Bonferroni
count) on every cached case of a power table's rows, from their seed sets alone (``outputs/fresh<BASE>_<row>/case_*``
as ``bench_diagnose_null.py`` made them; the frame channels never read the fit): which cases the lens's motion reading
names, under the floors in use, for every hidden effect and the clean cases.

Usage::

    PYTHONPATH=. python results/diagnose/null/centre_s100/frame_rows.py 13000 [ROW...] --out OUT.json

(ROW: the rows' names after ``fresh<BASE>_``, e.g. ``clean compression_alt``; none: every cached row.)
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from frame_recalibrate import case_channels  # noqa: E402  (the frame channels as the diagnosis screens them)


def main() -> int:
    from synthaug.data.seedset import SeedSet, seed_geometry
    from synthaug.diagnose import null_floors

    ap = argparse.ArgumentParser()
    ap.add_argument("base")
    ap.add_argument("rows", nargs="*", help="row names (fresh<BASE>_<row>); none: every cached row")
    ap.add_argument("--root", default="outputs")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    t0 = time.perf_counter()
    out = {"floors_in_use": dict(null_floors.SOURCE), "lens_frame_floor": null_floors.SCREEN["lens_distortion:frame"],
           "rows": {}}
    rows = [Path(a.root) / f"fresh{a.base}_{r}" for r in a.rows] or sorted(Path(a.root).glob(f"fresh{a.base}_*"))
    for row in rows:
        cases = []
        for case in sorted(row.glob("case_*")):
            seeds = SeedSet.load(case / "seeds")
            ch = case_channels(seeds, seed_geometry(seeds)).get("screen:lens_distortion:frame")
            cases.append(None if ch is None else {k: ch[k] for k in ("gain", "p_adjusted", "significant")})
        out["rows"][row.name] = cases
        named = sum(bool(c and c["significant"]) for c in cases)
        print(row.name, f"lens (frame) significant {named}/{len(cases)}",
              [None if c is None else round(c["gain"], 3) for c in cases], flush=True)
        if a.out:
            Path(a.out).write_text(json.dumps(out, indent=1))
    out["seconds"] = round(time.perf_counter() - t0, 1)
    if a.out:
        Path(a.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
