"""What a realism critic costs in ``SyntheticObjectDataset``: items/s with and without one, side by side (stop 84).

Usage::

    python benchmarks/bench_critic.py --repeats 5 --batches 4 --out results/bench/critic_speed.json

One process, one thread. The paper's patch mode (40×40, all four effects, half the items negative as by default),
16 sky backgrounds as seeds, a :class:`~synthaug.detectors.critic.RealismCritic` fitted once with
``RealismCritic.from_dataset`` on 16 real-looking sky patches. Variants: no critic, and the critic with
``realism_candidates`` 2, 4 and 8; each repeat runs every variant in turn (so they share the machine's load),
``__getitems__`` of ``--batch`` items ``--batches`` times after one warm-up batch, new indices every batch. Reported:
median items/s (wall and per CPU second of the process) over ``--repeats``, the critic's fit time, and the ratio to
no critic. ``uptime`` load averages at the start and end.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import time
from pathlib import Path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--batches", type=int, default=4)
    ap.add_argument("--batch", type=int, default=256)
    ap.add_argument("--candidates", type=int, nargs="+", default=[2, 4, 8])
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    import torch

    torch.set_num_threads(1)
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.synthetic import SyntheticObjectDataset
    from synthaug.detectors.critic import RealismCritic
    from synthaug.render.cache import ViewCache

    load_start = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    cache = ViewCache.build("quadcopter", step_deg=10, sprite_size=64)
    length = args.batch * (args.batches + 1) * args.repeats
    bgs = list(sky_backgrounds(16, (40, 40), seed=0))

    def dataset(k: int | None) -> SyntheticObjectDataset:
        return SyntheticObjectDataset("quadcopter", bgs, length=length, patch_size=40, render=cache, seed=0,
                                      realism_candidates=k or 4)

    plain = dataset(None)
    t = time.perf_counter()
    critic = RealismCritic.from_dataset(plain, sky_backgrounds(16, (40, 40), seed=1))
    fit_s = time.perf_counter() - t
    variants = {"no critic": plain}
    for k in args.candidates:
        ds = dataset(k)
        ds.realism_critic = critic
        variants[f"critic, {k} candidates"] = ds
    walls: dict[str, list[float]] = {n: [] for n in variants}
    cpus: dict[str, list[float]] = {n: [] for n in variants}
    for r in range(args.repeats):
        for name, ds in variants.items():
            base = r * args.batch * (args.batches + 1)
            ds.__getitems__(list(range(base, base + args.batch)))  # warm-up
            w = c = 0.0
            for b in range(1, args.batches + 1):
                idx = list(range(base + args.batch * b, base + args.batch * (b + 1)))
                t, p = time.perf_counter(), time.process_time()
                ds.__getitems__(idx)
                w += time.perf_counter() - t
                c += time.process_time() - p
            n = args.batch * args.batches
            walls[name].append(n / w)
            cpus[name].append(n / c)
    out = {
        "command": "python benchmarks/bench_critic.py " + " ".join(
            f"--{k.replace('_', '-')} {' '.join(map(str, v)) if isinstance(v, list) else v}"
            for k, v in vars(args).items() if v is not None),
        "setting": "patch 40x40, all four effects, negative_fraction 0.5, 16 seeds, one thread",
        "critic_fit_s": round(fit_s, 3),
        "items_per_s_median": {n: round(statistics.median(v), 1) for n, v in walls.items()},
        "items_per_cpu_s_median": {n: round(statistics.median(v), 1) for n, v in cpus.items()},
        "cpu_ratio_to_no_critic": {n: round(statistics.median(cpus["no critic"]) / statistics.median(v), 2)
                                   for n, v in cpus.items()},
        "repeats": {"items_per_s": walls, "items_per_cpu_s": cpus},
        "load_start": load_start,
        "load_end": subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip(),
    }
    text = json.dumps(out, indent=1)
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
