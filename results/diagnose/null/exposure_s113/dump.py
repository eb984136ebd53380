"""Issue 20, stop 113: per case, what auto-exposure's absorbed channel reads (the base render's re-solved w_d, the
frame brightness, the video) and each seed's precision of that w_d: ``ss`` the albedo template's energy (the sum of
squares of d render / d w_d over the patch) and ``rv`` the mean squared residual of the base render. Cases are
made first where missing (``--make BASE:HIDDEN:STRENGTH:CASES:WORKDIR``, the power bench's data and converged fit,
no diagnosis).

    PYTHONPATH=. python results/diagnose/null/exposure_s113/dump.py OUT_DIR CASE_DIR... [--make ...]
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[4] / "benchmarks"))


def make(spec):
    import bench_diagnose_null as bench

    base, hidden, strength, n, work = spec.split(":")
    args = ["--base-seed", base, "--strength", strength, "--workdir", work, "--cases", n, "--threads", "1"]
    a = bench.parser().parse_args(args + (["--hidden", hidden] if hidden != "clean" else []))
    return [str(bench.make_case(Path(work), k, a)[0].parent) for k in range(int(n))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--make", nargs="*", default=[])
    a = ap.parse_args()
    torch.set_num_threads(1)
    from synthaug.diagnose.diagnosis_data import albedo_renders, load_diagnosis_data, ALBEDO_POINTS
    from synthaug.diagnose.residuals import seed_groups, seed_metadata
    from synthaug.diagnose.screening import base_render

    cases = list(a.cases)
    for spec in a.make:
        cases += make(spec)
    os.makedirs(a.out, exist_ok=True)
    for case in cases:
        name = case.rstrip("/").replace("outputs/", "").replace("/", "__")
        f = f"{a.out}/{name}.npz"
        if os.path.exists(f):
            continue
        t = time.time()
        data = load_diagnosis_data(f"{case}/seeds", f"{case}/fit.json", "quadcopter")
        syn0, w0 = base_render(data, None)
        (v0, v1), (r0, r1) = ALBEDO_POINTS, albedo_renders(data, None)
        s = (r1.double() - r0.double()).flatten(1) / (v1 - v0)
        res = (data.real.double() - syn0.double()).flatten(1)
        md = seed_metadata(data)
        np.savez(f, w=w0.numpy(), B=md["frame_brightness"], g=seed_groups(data), n=len(data),
                 ss=(s * s).sum(1).numpy(), rv=(res * res).mean(1).numpy(), size=md["object_size"])
        print(name, round(time.time() - t, 1), flush=True)


if __name__ == "__main__":
    main()
