"""Issue 20, specular: is the candidate's fixed light what keeps it from being named?

The reference camera lights each video from its own direction (``Nuisances.light_spread_deg``: 10-40 deg from
the model's), and a hidden highlight sits where n.h peaks for *that* light; the specular candidate
(``synthaug.effects.camera.Specular``) draws it for the model's default light. On each case of a power run
(``bench_diagnose_null.py --hidden specular --workdir DIR``) this script screens the specular grid twice, with
the model's light and with each seed's true light (read from the seed records' truth), and prints the
screening's pixel- and feature-space held-out gains of both (same folds, same penalty as the diagnosis).

    PYTHONPATH=. python results/diagnose/null/specular_light.py outputs/bench_diagnose_power5_specular{,_alt}/case_00?
"""
from __future__ import annotations

import sys

import numpy as np
import torch

import synthaug.effects.camera as camera
from synthaug.data.seedset import SeedSet
from synthaug.diagnose import screening as S
from synthaug.diagnose.diagnosis_data import load_diagnosis_data


def screen(data, folds, base, light):
    old = camera.DEFAULT_LIGHT
    try:
        if light is not None:
            camera.DEFAULT_LIGHT = light  # read by Specular.apply at call time; (N, 3) per seed
        r = S.screen_one(data, "specular", folds, base)
    finally:
        camera.DEFAULT_LIGHT = old
    return {sp: (r[sp]["gain"], r[sp]["p"]) for sp in ("feature", "pixel")}


def main(cases):
    print(f"{'case':44s} {'model light: feature / pixel gain (p)':44s} true light: feature / pixel gain (p)")
    for case in cases:
        seeds = SeedSet.load(f"{case}/seeds")
        data = load_diagnosis_data(seeds, f"{case}/fit.json", "quadcopter")
        light = [r["truth"]["nuisance"]["light_dir"] for r in seeds.records]
        folds = S.kfold(len(data), 5, np.random.default_rng(0))
        syn, w = S.base_render(data)
        base = (S.pairwise_distance(data, syn), S.pixel_distance(data.real, syn))
        a = screen(data, folds, base, None)
        # one chunk: the grid renders every seed at once for fewer than 128 seeds
        b = screen(data, folds, base, torch.tensor(light, dtype=torch.float32))
        fmt = lambda d: " / ".join(f"{d[s][0]:+.4f} ({d[s][1]:.1e})" for s in ("feature", "pixel"))
        print(f"{case:44s} {fmt(a):44s} {fmt(b)}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
