"""Issue 20, stop 111: per-seed normal equations of highlight estimators, cached for offline comparison.

For each case: the regressors of every seed (flattened patch pixels) — the albedo slope s, the specular template at
exponents SHINES (ks 1, the model's light and normals), the object layer's shift derivatives gx, gy and its scale
derivative gs — with y = real − render(w_d 0.2). Saves X'X, X'y, y'y, the pixel count, the hidden ks and the clean
nuisance ks per seed, so any subset model (and its per-seed standard errors) is solved offline (compare.py).

    PYTHONPATH=. python results/diagnose/null/highlight_s111/gram.py OUT.npz CASE_DIR...
    SHINES=120,160,240 PYTHONPATH=. python ...  # other exponents (default 10,20,30,45,80)
    MASK=rotor ROTOR_MAX=0.5 PYTHONPATH=. python ...  # pixels of the model's rotor parts (> ROTOR_MAX) left out
"""
import os
import sys

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.diagnose import screening as S
from synthaug.diagnose.diagnosis_data import ALBEDO_POINTS, albedo_renders, load_diagnosis_data, render_with

SHINES = tuple(float(e) for e in os.environ.get("SHINES", "10,20,30,45,80").split(","))
COLS = ["s"] + [f"h{int(e)}" for e in SHINES] + ["gx", "gy", "gs"]


def load_case(case: str):
    """A cached case's seed set and its diagnosis data (its fit, the built-in quadcopter)."""
    seeds = SeedSet.load(f"{case}/seeds")
    return seeds, load_diagnosis_data(seeds, f"{case}/fit.json", "quadcopter")


def slope_and_templates(data, shines):
    """The model's render at w_d 0.2 (``a0``) and the columns against it: the albedo slope, then the specular template
    (ks 1) at each exponent of ``shines``, all (N, 1, P, P) float64."""
    n, (w0, w1), (r0, r1) = len(data), ALBEDO_POINTS, albedo_renders(data, None)
    a0 = r0.double()
    cols = [(r1.double() - a0) / (w1 - w0)]
    for e in shines:
        ext = S.extension_values(data, "specular", {"specular_ks": 1.0, "specular_shininess": e})
        cols.append(render_with(data, ext, w_d=torch.full((n,), w0), clamp=False).double() - a0)
    return a0, cols


def case_gram(case: str) -> dict:
    seeds, data = load_case(case)
    a0, cols = slope_and_templates(data, SHINES)
    r = render_with(data, None, clamp=False).double()  # at the fitted w_d
    al = data.coverage.double()
    gx, gy = shift_derivatives(data, r)
    p = r.shape[-1]
    yy_, xx_ = torch.meshgrid(torch.arange(p, dtype=torch.float64), torch.arange(p, dtype=torch.float64), indexing="ij")
    m = al.sum((-1, -2), keepdim=True).clamp_min(1e-6)
    cx, cy = (al * xx_).sum((-1, -2), keepdim=True) / m, (al * yy_).sum((-1, -2), keepdim=True) / m
    gs = (xx_ - cx) * gx + (yy_ - cy) * gy
    cols += [gx, gy, gs]
    X = torch.stack([c.flatten(1) for c in cols], -1)  # (N, P, K)
    y = (data.real.double() - a0).flatten(1)
    if os.environ.get("MASK") == "rotor" and data.part_rotor is not None:  # the rotors' pixels left out
        keep = (data.part_rotor.double().flatten(1) <= float(os.environ.get("ROTOR_MAX", "0.5"))).double()
        X, y = X * keep[..., None], y * keep
    G = torch.einsum("npk,npl->nkl", X, X).numpy()
    b = torch.einsum("npk,np->nk", X, y).numpy()
    yy = (y * y).sum(1).numpy()
    return {"G": G, "b": b, "yy": yy, "npix": y.shape[1], **specular_truth(seeds, case)}


def shift_derivatives(data, r):
    """The object layer's shift derivatives (x, y) of the render ``r`` over its background: central differences, 0 on
    the patch's border."""
    bg, al = data.background.double(), data.coverage.double()
    dx = lambda t: (torch.roll(t, -1, -1) - torch.roll(t, 1, -1)) / 2  # noqa: E731
    dy = lambda t: (torch.roll(t, -1, -2) - torch.roll(t, 1, -2)) / 2  # noqa: E731
    gx, gy = dx(r) - (1 - al) * dx(bg), dy(r) - (1 - al) * dy(bg)
    for t in (gx, gy):
        t[..., 0] = 0; t[..., -1] = 0; t[..., 0, :] = 0; t[..., -1, :] = 0  # noqa: E702
    return gx, gy


def specular_truth(seeds, case):
    """What the case hides: each seed's hidden ``specular_ks`` (0 without) and the clean material's (ks, exponent)."""
    import json
    import pathlib

    hid = np.array([rec["truth"]["hidden"].get("specular", {}).get("specular_ks", 0.0) for rec in seeds.records])
    cj = pathlib.Path(case) / "case.json"
    nz = json.loads(cj.read_text())["key"].get("nuisances") or {} if cj.exists() else {}
    return {"hidden_ks": hid, "nuis_ks": np.array([nz.get("specular_ks", np.nan), nz.get("specular_shininess", np.nan)],
                                                  float)}


def run_cases(fn, label, names, echo=None) -> int:
    """``OUT.npz CASE_DIR...`` from the command line: ``fn(case)`` (a dict of arrays) for each case, saved as
    ``{i}:{key}`` beside ``cases`` and ``label`` = ``names`` (the columns); ``echo(result)`` printed after each case's
    name."""
    torch.set_num_threads(1)
    out, cases = sys.argv[1], sys.argv[2:]
    res = {}
    for i, c in enumerate(cases):
        g = fn(c)
        for k, v in g.items():
            res[f"{i}:{k}"] = v
        print(c, *([echo(g)] if echo else []), flush=True)
    np.savez(out, cases=np.array(cases), **{label: np.array(names)}, **res)
    return 0


def main() -> int:
    return run_cases(case_gram, "cols", COLS, echo=lambda g: len(g["yy"]))


if __name__ == "__main__":
    sys.exit(main())
