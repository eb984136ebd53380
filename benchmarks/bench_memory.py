"""Memory benchmark (issue 18, item 6): resident memory of the main process and of the DataLoader workers while a
``SyntheticObjectDataset`` streams ``--samples`` patches through 2 persistent workers.

Usage::

    python benchmarks/bench_memory.py                    # 50,000 samples, prints one JSON object
    python benchmarks/bench_memory.py --samples 5000 --every 10

Setup: the built-in ``quadcopter`` mesh, patch mode (40 px, all default effects), backgrounds from a small
generated seed set (``--seeds`` procedural sky seeds written with ``write_seedset`` to a temporary folder, no
real data needed), ``DataLoader(num_workers=2, persistent_workers=True)`` with an
:class:`~synthaug.data.synthetic.EpochSampler` so every epoch (``--epoch-length`` samples) draws new poses.

Every ``--every`` batches it records the resident set size (VmRSS from ``/proc/<pid>/status``) and the
proportional set size (Pss from ``/proc/<pid>/smaps_rollup``: shared pages split between the processes that map
them, so the sum is not inflated by copy-on-write pages the workers share with the main process) of the main
process and of all its descendants (the workers). ``flat`` is true when the last total RSS is within 10 % of the
total after the first 10 % of the samples (the issue's criterion); ``flat_pss`` the same for PSS.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path


def _status_kib(pid: int, field: str = "VmRSS") -> int:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def _pss_kib(pid: int) -> int:
    try:
        for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
            if line.startswith("Pss:"):
                return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def _descendants(root: int) -> list[int]:
    """Every live descendant of ``root`` (by the parent field of /proc/<pid>/stat)."""
    parent: dict[int, int] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
                parent[int(d.name)] = int(stat[stat.rindex(")") + 2:].split()[1])
            except (OSError, ValueError):
                continue
    out, frontier = [], [root]
    while frontier:
        p = frontier.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        out += kids
        frontier += kids
    return out


def _sample(samples_done: int, t0: float) -> dict:
    me = os.getpid()
    kids = _descendants(me)
    return {"samples": samples_done, "t_s": round(time.perf_counter() - t0, 1),
            "main_rss_mib": round(_status_kib(me) / 1024, 1),
            "workers_rss_mib": round(sum(_status_kib(p) for p in kids) / 1024, 1),
            "main_pss_mib": round(_pss_kib(me) / 1024, 1),
            "workers_pss_mib": round(sum(_pss_kib(p) for p in kids) / 1024, 1),
            "processes": 1 + len(kids)}


def _make_seedset(root: Path, n: int):
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import SeedSet, write_seedset

    bgs = sky_backgrounds(n, (40, 40), seed=0)
    patches = bgs.copy()
    patches[:, 15:25, 10:30] = 30
    frames = sky_backgrounds(n, (96, 96), seed=1)
    write_seedset(root / "seeds", patches=patches, backgrounds=bgs, boxes=[[10, 15, 20, 10]] * n,
                  centres=[[20, 20]] * n, crops=[[20, 20, 40]] * n, records=[{"video": "generated"}] * n,
                  frames=list(frames), background_frames=list(frames),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    return SeedSet.load(root / "seeds")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=50_000, help="samples to draw in all (default 50,000)")
    parser.add_argument("--epoch-length", type=int, default=5_000, help="samples per epoch (new poses each epoch)")
    parser.add_argument("--batch-size", type=int, default=64)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--every", type=int, default=20, help="record memory every N batches")
    parser.add_argument("--seeds", type=int, default=8, help="generated seeds in the seed set")
    parser.add_argument("--step-deg", type=float, default=10.0, help="view-cache step")
    args = parser.parse_args()
    for name in ("samples", "epoch_length", "batch_size", "workers", "every", "seeds"):
        if getattr(args, name) < (0 if name == "workers" else 1):
            parser.error(f"--{name.replace('_', '-')} must be >= {0 if name == 'workers' else 1}")

    import torch
    from torch.utils.data import DataLoader

    from synthaug.data.synthetic import EpochSampler, SyntheticObjectDataset

    with tempfile.TemporaryDirectory() as tmp:
        seeds = _make_seedset(Path(tmp), args.seeds)
        ds = SyntheticObjectDataset("quadcopter", seeds, length=args.epoch_length, mode="patch", patch_size=40,
                                    seed=0, render={"step_deg": args.step_deg})
        sampler = EpochSampler(ds)
        loader = DataLoader(ds, batch_size=args.batch_size, sampler=sampler, num_workers=args.workers,
                            persistent_workers=args.workers > 0)
        t0 = time.perf_counter()
        curve = [_sample(0, t0)]
        done, batches, epoch, checksum = 0, 0, 0, 0.0
        while done < args.samples:
            sampler.set_epoch(epoch)
            for images, _ in loader:
                done += images.shape[0]
                batches += 1
                checksum += float(images[:, :, ::8, ::8].sum())
                if batches % args.every == 0:
                    curve.append(_sample(done, t0))
                if done >= args.samples:
                    break
            epoch += 1
        if curve[-1]["samples"] != done:
            curve.append(_sample(done, t0))
        wall = time.perf_counter() - t0
        del loader

    def total(p, kind="rss"):
        return p[f"main_{kind}_mib"] + p[f"workers_{kind}_mib"]

    ref = next(p for p in curve if p["samples"] >= 0.1 * done)
    last = curve[-1]
    result = {
        "benchmark": "memory", "command": " ".join(["python benchmarks/bench_memory.py", *sys.argv[1:]]),
        "samples": done, "epochs": -(-done // args.epoch_length),
        "workers": args.workers, "persistent_workers": args.workers > 0, "batch_size": args.batch_size,
        "wall_s": round(wall, 1), "samples_per_s": round(done / wall, 1), "torch": torch.__version__,
        "reference": {"samples": ref["samples"], "total_rss_mib": round(total(ref), 1),
                      "total_pss_mib": round(total(ref, "pss"), 1)},
        "last": {"samples": last["samples"], "total_rss_mib": round(total(last), 1),
                 "total_pss_mib": round(total(last, "pss"), 1)},
        "rss_change": round(total(last) / total(ref) - 1, 4),
        "pss_change": round(total(last, "pss") / max(total(ref, "pss"), 1e-9) - 1, 4),
        "flat": abs(total(last) / total(ref) - 1) <= 0.10,
        "flat_pss": abs(total(last, "pss") / max(total(ref, "pss"), 1e-9) - 1) <= 0.10,
        "peak_total_rss_mib": round(max(total(p) for p in curve), 1),
        "checksum": round(checksum, 3),
        "curve": curve,
    }
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
