"""Speed of the candidate camera effects and of the reference camera.

One command, prints JSON (medians):

    python benchmarks/bench_camera_effects.py [--batch 256] [--size 40] [--repeats 7] [--seeds 20]

``effects``: ms per call of ``simulate`` with the paper's four effects plus one
candidate, for a fit-sized population (batch × 1 × size × size, float32, one
thread), and the paper-only baseline. ``reference_camera``: seconds per seed of
:func:`make_measured_seedset` (320 × 256 frames, warm view cache).
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time

import torch

import synthaug.effects.camera  # noqa: F401
from synthaug.effects import PAPER_EFFECTS, sample_fields, simulate
from synthaug.effects.camera import CAMERA_EFFECTS
from synthaug.params import CaptureParams


def _median_ms(fn, repeats: int) -> float:
    fn()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1000 * statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--batch", type=int, default=256)
    ap.add_argument("--size", type=int, default=40)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--seeds", type=int, default=20)
    args = ap.parse_args()
    torch.set_num_threads(1)
    g = torch.Generator().manual_seed(0)
    b, s = args.batch, args.size
    cov = torch.zeros(b, 1, s, s)
    cov[..., s // 4:3 * s // 4, s // 4:3 * s // 4] = 1.0
    nrm = torch.zeros(b, 3, s, s)
    nrm[:, 2] = cov[:, 0]
    bg = torch.rand(b, 1, s, s, generator=g) * 0.5 + 0.3
    origin = torch.rand(b, 2, generator=g) * 200
    fsize = torch.tensor([[320.0, 256.0]]).expand(b, 2)
    extras = {"frame_scale": torch.full((b,), 1.2)}
    out: dict = {"batch": b, "size": s, "threads": 1, "effects_ms": {}}
    for name in ("paper_only",) + CAMERA_EFFECTS:
        effects = PAPER_EFFECTS if name == "paper_only" else PAPER_EFFECTS + (name,)
        theta = CaptureParams.sample(b, generator=g, effects=effects)
        fields = sample_fields(effects, (b, 1, s, s), g)
        out["effects_ms"][name] = round(_median_ms(
            lambda: simulate(cov, nrm, bg, theta, fields=fields, origin=origin, frame_size=fsize, extras=extras),
            args.repeats), 2)
    from synthaug.diagnose.reference_camera import make_measured_seedset

    with tempfile.TemporaryDirectory() as d:
        make_measured_seedset(f"{d}/warm", n_seeds=1)  # builds the view caches
        for label, hidden in (("clean", {}), ("all_candidates", {n: {} for n in CAMERA_EFFECTS})):
            t = time.perf_counter()
            make_measured_seedset(f"{d}/{label}", n_seeds=args.seeds, hidden=hidden)
            out.setdefault("reference_camera_s_per_seed", {})[label] = round((time.perf_counter() - t) / args.seeds, 4)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
