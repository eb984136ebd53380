"""Issue 20, sharpening: the frames' edge ratio (``frame_pattern.edge_ratio``) on reference-camera cases, per case.

Generates nuisance-varied seed sets as ``bench_diagnose_null.py`` does (base seed 8000, case k's nuisances and seed;
no fit: the ratio reads the frames only) for clean cases and for hidden effects that change edges or noise, and
prints each case's mean ratio over its 60 frames, read on the frame at edges found on its independent background
frame, beside the same ratio with the edges found on the frame itself ("same look", the design it replaces).

    PYTHONPATH=. python results/diagnose/null/edge_ratio_cases.py [--workdir outputs/edge_ratio_cases]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))

RUNS = ([("clean", "default", k) for k in range(30)] + [("sharpening", "default", k) for k in range(10)]
        + [("sharpening", "alt", k) for k in range(10)]
        + [(e, s, k) for e in ("column_pattern",) for s in ("default", "alt") for k in range(5)]
        + [(e, "default", k) for e in ("shot_noise", "gamma", "defocus", "compression") for k in range(5)])


def main() -> None:
    from bench_diagnose_null import hidden_settings

    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.frame_pattern import edge_ratio
    from synthaug.diagnose.nuisances import Nuisances
    from synthaug.diagnose.reference_camera import make_measured_seedset

    ap = argparse.ArgumentParser()
    ap.add_argument("--workdir", default="outputs/edge_ratio_cases")
    a = ap.parse_args()
    t0 = time.perf_counter()
    rows: dict[str, list[tuple[float, float]]] = {}
    for eff, strength, k in RUNS:
        out = Path(a.workdir) / f"{eff}_{strength}_{k}"
        if not (out / "seedset.json").exists():
            make_measured_seedset(out, n_seeds=60, hidden=None if eff == "clean" else hidden_settings(eff, strength),
                                  nuisances=Nuisances.draw(np.random.default_rng([8000, k])), colour=False,
                                  frame_size=(192, 256), object_px=(20.0, 32.0), view_step_deg=20.0, sprite_size=48,
                                  seed=8000 + k, paper_ranges={"w_d": (0.3, 0.45)})
        s = SeedSet.load(out)
        v = []
        for i in range(len(s)):
            f = np.asarray(s.frame(i)).astype(np.float64) / 255.0
            b = np.asarray(s.background_frame(i)).astype(np.float64) / 255.0
            v.append((edge_ratio(f, b), edge_ratio(f, f + 1e-3)))  # same look: 1/1000 apart, no pixel equal
        v = np.array(v)
        rows.setdefault(f"{eff} {strength}", []).append(tuple(np.nanmean(v, 0)))
    print("| cases | n | edge ratio, independent look: min / mean / max | same look: min / mean / max |")
    print("|---|---|---|---|")
    for name, r in rows.items():
        x = np.array(r)
        print(f"| {name} | {len(x)} | {x[:, 0].min():.3f} / {x[:, 0].mean():.3f} / {x[:, 0].max():.3f} | "
              f"{x[:, 1].min():.3f} / {x[:, 1].mean():.3f} / {x[:, 1].max():.3f} |")
    print(f"\nwall {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
