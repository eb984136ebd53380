"""Rendering speed, this tree against a baseline commit, side by side in one run (issue 19).

Usage::

    python benchmarks/bench_speed_render.py --what getitems loader_patch loader_frame --repeats 3 \\
        --batches 8 --loader-batches 20 --out results/bench/render_speed_vs_ed00d8d.json

The baseline's ``synthaug/`` is extracted with ``git archive`` into a
temporary folder and put first on ``PYTHONPATH`` of its subprocesses, so both
variants run the same measuring code in fresh interpreters, alternately
(baseline, new, baseline, new, ...), so that they share the load of a shared
machine. Measured:

- ``getitems``: one process, one thread, ``SyntheticObjectDataset.__getitems__``
  of 256 64×64 patches (all four effects), samples/s over ``--batches``
  batches after one warm-up batch; ``getitems_cpu`` the same per second of
  the process's CPU time (less sensitive to other jobs on a shared machine);
- ``loader_patch`` / ``loader_frame``: ``synthaug bench render --mode patch
  --patch-size 64 --workers 2`` and ``--mode frame`` (640×512, 2 workers).

Also an equivalence check: the same 256 patch items and 32 frames (same seed,
epoch and indices) from both variants, max |new - baseline| (float rounding,
but for the rare pixel where rounding crosses the motion blur's 1e-6 coverage
cut-off; ``tests/test_render_fast_paths.py`` bounds both).
Medians of ``--repeats`` runs per variant; ``uptime`` load averages are
recorded at the start and end.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_GETITEMS = r"""
import json, sys, time, torch
torch.set_num_threads(1)
from synthaug.data.procedural import sky_backgrounds
from synthaug.data.synthetic import SyntheticObjectDataset
batches = int(sys.argv[1])
bgs = sky_backgrounds(16, (128, 128), seed=0)
ds = SyntheticObjectDataset("quadcopter", bgs, length=256 * (batches + 1), mode="patch", patch_size=64,
                            negative_fraction=0.0, seed=0, cache_options={"step_deg": 5.0})
ds.__getitems__(list(range(256)))  # warm-up
walls, cpus = [], []
for b in range(1, batches + 1):
    t, c = time.perf_counter(), time.process_time()
    ds.__getitems__(list(range(256 * b, 256 * (b + 1))))
    walls.append(time.perf_counter() - t)
    cpus.append(time.process_time() - c)
print(json.dumps({"samples_per_s": 256 * batches / sum(walls), "samples_per_cpu_s": 256 * batches / sum(cpus)}))
"""

_ITEMS = r"""
import sys, torch
from synthaug.data.procedural import sky_backgrounds
from synthaug.data.synthetic import SyntheticObjectDataset
out = {}
bgs = sky_backgrounds(16, (128, 128), seed=0)
ds = SyntheticObjectDataset("quadcopter", bgs, length=512, mode="patch", patch_size=64,
                            negative_fraction=0.0, seed=3, cache_options={"step_deg": 5.0})
out["patch"] = torch.stack([img for img, _ in ds.__getitems__(list(range(256)))])
bgs = sky_backgrounds(4, (512, 640), seed=0)
ds = SyntheticObjectDataset("quadcopter", bgs, length=64, mode="frame", negative_fraction=0.0, seed=3,
                            cache_options={"step_deg": 5.0})
out["frame"] = torch.stack([img.as_subclass(torch.Tensor) for img, _ in ds.__getitems__(list(range(32)))])
torch.save(out, sys.argv[1])
"""


def _load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3]) if Path("/proc/loadavg").exists() else "?"


def _run(code_or_args: list[str], pythonpath: str) -> str:
    # cwd is a neutral folder: with ``python -c`` the working directory comes first on sys.path
    env = dict(os.environ)
    env["PYTHONPATH"] = pythonpath + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    code = ("import synthaug, sys; assert synthaug.__file__.startswith(sys.argv.pop(1)), synthaug.__file__\n"
            + code_or_args[1]) if code_or_args[0] == "-c" else None
    argv = ["-c", code, pythonpath, *code_or_args[2:]] if code else code_or_args
    r = subprocess.run([sys.executable, *argv], env=env, capture_output=True, text=True, cwd=tempfile.gettempdir())
    if r.returncode:
        raise RuntimeError(f"{code_or_args[:2]} failed:\n{r.stderr[-3000:]}")
    return r.stdout


def _loader(mode: str, workers: int, batches: int, pythonpath: str) -> float:
    out = _run(["-c", "import sys; from synthaug.cli import main; sys.exit(main())", "bench", "render",
                "--mode", mode, "--patch-size", "64", "--workers", str(workers), "--repeats", "3",
                "--batches", str(batches)], pythonpath)
    return float(json.loads(out)["results"][0]["samples_per_s_median"])


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--baseline", default="ed00d8d", help="git revision of today's path")
    p.add_argument("--repeats", type=int, default=3, help="runs per variant (alternating)")
    p.add_argument("--batches", type=int, default=8, help="timed 256-item batches per getitems run")
    p.add_argument("--loader-batches", type=int, default=20, help="--batches of each `synthaug bench render`")
    p.add_argument("--what", nargs="+", default=["getitems", "loader_patch", "loader_frame"],
                   choices=["getitems", "loader_patch", "loader_frame"])
    p.add_argument("--out", type=Path, default=None, help="write the JSON here too")
    args = p.parse_args()

    rev = subprocess.run(["git", "rev-parse", "--short", args.baseline], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.strip()
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                          text=True, check=True).stdout.strip()
    dirty = bool(subprocess.run(["git", "status", "--porcelain", "--", "synthaug"], cwd=ROOT,
                                capture_output=True, text=True).stdout.strip())
    result: dict = {"benchmark": "render_speed_side_by_side", "baseline": rev, "new": head + ("+dirty" if dirty else ""),
                    "command": " ".join(["python", "benchmarks/bench_speed_render.py", *sys.argv[1:]]),
                    "load_start": _load(), "cpu_count": os.cpu_count()}
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        base.mkdir()
        arch = subprocess.run(["git", "archive", rev, "synthaug"], cwd=ROOT, capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(base)], input=arch, check=True)
        variants = {"baseline": str(base), "new": str(ROOT)}

        # equivalence: same items from both
        items = {}
        for name, pp in variants.items():
            f = Path(tmp) / f"{name}.pt"
            _run(["-c", _ITEMS, str(f)], pp)
            import torch

            items[name] = torch.load(f)
        result["max_abs_diff"] = {k: float((items["new"][k] - items["baseline"][k]).abs().max()) for k in items["new"]}

        runs: dict[str, dict[str, list[float]]] = {w: {"baseline": [], "new": []} for w in args.what}
        for rep in range(args.repeats):
            for what in args.what:
                for name, pp in variants.items():
                    if what == "getitems":
                        g = json.loads(_run(["-c", _GETITEMS, str(args.batches)], pp))
                        v = g["samples_per_s"]
                        runs.setdefault("getitems_cpu", {"baseline": [], "new": []})[name].append(
                            round(g["samples_per_cpu_s"], 1))
                    else:
                        v = _loader(what.split("_")[1], 2, args.loader_batches, pp)
                    runs[what][name].append(round(v, 1))
                    print(f"rep {rep} {what:13s} {name:8s} {v:8.1f}/s  load {_load()}", file=sys.stderr, flush=True)
    result["load_end"] = _load()
    result["runs"] = runs
    result["median"] = {w: {n: statistics.median(v) for n, v in r.items()} for w, r in runs.items()}
    result["speedup"] = {w: round(m["new"] / m["baseline"], 2) for w, m in result["median"].items()}
    text = json.dumps(result, indent=1)
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
