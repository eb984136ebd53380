"""Issue 20: does the frames' edge sharpness change with the distance from the centre under a lens, and not under
in-camera sharpening? (Lens k1 +0.1, case 4 of the power table, has no scene motion to read the lens from, and
its frames' mean edge ratio, 0.650, passes sharpening's floor, 0.647.)

For each case (the power table's and the calibration's cases: the same seeds, nuisances and hidden settings as
``benchmarks/bench_diagnose_null.py``; only the seed set is made, no fit: the frame statistics do not read it),
each frame's edges are those :func:`synthaug.diagnose.frame_pattern.edge_ratio` reads (``edge_steps``), and the
per-edge steps A(2), A(4) are fitted as ``A(2) = (a + b r^2) A(4)`` by least squares over the frame's edges (r^2
as the vignetting reads it: 1 at the frame's corners). Prints per case the frames' mean ratio, mean ``a`` and mean
``b``, and writes them as JSON.

Usage::

    PYTHONPATH=. python results/diagnose/null/edge_radial.py --out results/diagnose/null/edge_radial.json \
        clean:2000:24 lens_distortion:alt:8000:5 sharpening:default:8000:5 sharpening:alt:8000:5
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

import numpy as np

from synthaug.diagnose import frame_pattern as fp


def frame_fit(r2: np.ndarray, a1: np.ndarray, a2: np.ndarray) -> tuple[float, float, float]:
    """(ratio, a, b): the frame's edge ratio and the least-squares fit of A1 = (a + b r^2) A2."""
    x = np.stack([a2, a2 * r2], 1)
    (a, b), *_ = np.linalg.lstsq(x, a1, rcond=None)
    return float(a1.sum() / a2.sum()), float(a), float(b)


def case_frames(work: Path, base: int, k: int, hidden: str | None, strength: str, *, full: bool = False):
    """Case ``k``'s seed set as ``bench_diagnose_null.py`` makes it (``case_seedset``; ``full``: for its full fit at
    the default views), made once under ``work``."""
    from benchmarks.bench_diagnose_null import CONVERGED_VIEWS, FULL_FIT_VIEWS, case_seedset
    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.nuisances import Nuisances

    seeds_dir = work / f"case_{k:03d}"
    done = seeds_dir / "done"
    if not done.exists():
        if seeds_dir.exists():
            shutil.rmtree(seeds_dir)
        nz = Nuisances.draw(np.random.default_rng([base, k]))
        case_seedset(seeds_dir, k, base_seed=base, n_seeds=60, nuisances=nz, hidden=hidden, strength=strength,
                     views=FULL_FIT_VIEWS if full else CONVERGED_VIEWS)
        done.write_text("1")
    seeds = SeedSet.load(seeds_dir)
    return seeds


def group_cases(group: str, workdir: str | Path):
    """The cases of a group, ``clean:BASE:N`` or ``EFFECT:STRENGTH:BASE:N``, either with ``:full`` appended for the
    seed sets of ``bench_diagnose_null.py --fit full --step-deg 10 --sprite-size 64`` (its sprites and views follow
    the fit's; without it, the converged fit's 48 px and 20 degrees): (k, seed set, its geometry) for k < N, each seed
    set made once under ``workdir``."""
    from synthaug.data.seedset import seed_geometry

    parts = group.split(":")
    full = parts[-1] == "full"
    parts = parts[:-1] if full else parts
    if parts[0] == "clean":
        hidden, strength, base, n = None, "default", int(parts[1]), int(parts[2])
    else:
        hidden, strength, base, n = parts[0], parts[1], int(parts[2]), int(parts[3])
    for k in range(n):
        seeds = case_frames(Path(workdir) / group.replace(":", "_"), base, k, hidden, strength, full=full)
        yield k, seeds, seed_geometry(seeds)


def run_groups(groups, workdir: str | Path, case_row, *, key: str = "k", show=None, out_path: str | None = None,
               t0: float | None = None) -> dict:
    """The scripts' loop over the groups' cases: ``{"groups": {group: [{key: k, **case_row(seeds, geo)}, ...]}}``,
    each row printed as it comes (``show(group, row)``, or the row itself); with ``out_path`` the JSON written after
    every group (:func:`write_out`, wall time since ``t0``)."""
    out: dict = {"groups": {}}
    for group in groups:
        rows = []
        for k, seeds, geo in group_cases(group, workdir):
            rows.append({key: k, **case_row(seeds, geo)})
            if show is None:
                print(group, rows[-1], flush=True)
            else:
                show(group, rows[-1])
        out["groups"][group] = rows
        if out_path:
            write_out(out, out_path, t0)
    return out


def write_out(out: dict, path: str | None, t0: float) -> int:
    """The scripts' last step: the wall time since ``t0`` into ``out``, ``out`` as JSON at ``path`` (if given)."""
    import time

    out["seconds"] = round(time.perf_counter() - t0, 1)
    if path:
        Path(path).write_text(json.dumps(out, indent=1))
    return 0


def groups_parser() -> argparse.ArgumentParser:
    """The command line of this script and of ``edge_radial_scenes.py``: the groups of cases, their work folder and
    the JSON out."""
    ap = argparse.ArgumentParser()
    ap.add_argument("groups", nargs="+", help="clean:BASE:N or EFFECT:STRENGTH:BASE:N, optionally with :full")
    ap.add_argument("--workdir", default="outputs/edge_radial")
    ap.add_argument("--out", default=None)
    return ap


def main() -> int:
    a = groups_parser().parse_args()

    out = {}
    for group in a.groups:
        rows = []
        for k, seeds, geo in group_cases(group, a.workdir):
            p = seeds.patch_size
            per = []
            for i in range(len(seeds)):
                f, bg = np.asarray(seeds.frame(i)), np.asarray(seeds.background_frame(i))
                h, w = f.shape[:2]
                outside = np.ones((h, w), bool)
                x0, y0, side = float(geo["origin"][i, 0]), float(geo["origin"][i, 1]), p * float(geo["frame_scale"][i])
                outside[int(max(0, np.floor(y0 - 2))):int(np.ceil(y0 + side + 2)),
                        int(max(0, np.floor(x0 - 2))):int(np.ceil(x0 + side + 2))] = False
                s = fp.edge_steps(fp._gray(f), fp._gray(bg), outside=outside)  # the edges edge_ratio reads
                if s is not None:
                    (fh, fw), y, x = s["shape"], s["y"], s["x"]
                    r2 = ((x - (fw - 1) / 2) ** 2 + (y - (fh - 1) / 2) ** 2) / (0.25 * (fw * fw + fh * fh))
                    per.append(frame_fit(r2, s["a1"], s["a2"]))
            per = np.array(per)
            row = {"k": k, "frames": int(len(per)), "ratio": float(per[:, 0].mean()), "a": float(per[:, 1].mean()),
                   "b": float(per[:, 2].mean()), "b_t": float(per[:, 2].mean() / (per[:, 2].std(ddof=1) / np.sqrt(len(per))))}
            rows.append(row)
            print(group, row, flush=True)
        out[group] = rows
    if a.out:
        Path(a.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
