"""Issue 20, stop 112: the highlight template at each video's light ESTIMATED from the objects' diffuse shading — what
gram_light.py's oracle (the true light) would be worth in practice. Per case: the albedo slope at 13 lights (the
model's, and tilted by 15 and 30 degrees at 6 azimuths); per video the light whose diffuse fit (real − render(w_d 0.2)
on the albedo slope, seed by seed) leaves the least squared residual over the video's seeds; then the template
(exponent 80) at each seed's video light. Columns ``s``, ``h80`` (the model's light, the library's), ``sE``, ``h80E``
(the estimated light; ``yyE`` their y'y). Offline only: the light rides in the render's extras as in gram_light.py.

    PYTHONPATH=. python results/diagnose/null/highlight_s112/light_grid.py OUT.npz CASE_DIR...
"""
import json
import math
import pathlib
import sys

import numpy as np
import torch

from gram_light import LIGHT  # importing it patches the pipeline's simulate to take LIGHT
from synthaug.diagnose import screening as S
from synthaug.diagnose.diagnosis_data import ALBEDO_POINTS, albedo_renders, render_with
from synthaug.diagnose.nuisances import MODEL_LIGHT

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from gram import load_case, run_cases, specular_truth  # noqa: E402  (stop 111's)

COLS = ["s", "h80", "sE", "h80E"]


def tilted(tilt_deg, az):
    """MODEL_LIGHT tilted by ``tilt_deg`` toward azimuth ``az`` (about the axis orthogonal to it)."""
    l0 = np.asarray(MODEL_LIGHT, float)
    u = np.cross(l0, [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(l0, u)
    d = math.cos(az) * u + math.sin(az) * v
    t = math.radians(tilt_deg)
    return math.cos(t) * l0 + math.sin(t) * d


GRID = [np.asarray(MODEL_LIGHT, float)] + [tilted(t, a * math.pi / 3) for t in (15.0, 30.0) for a in range(6)]


def case_gram(case: str) -> dict:
    seeds, data = load_case(case)
    n, (w0, w1) = len(data), ALBEDO_POINTS
    vids = [r["video"] for r in json.loads((pathlib.Path(case) / "seeds" / "seedset.json").read_text())["records"]]
    real = data.real.double().flatten(1)
    a0s, ss, rss = [], [], []
    for light in GRID:
        LIGHT[0] = torch.tensor(light, dtype=torch.float32)
        r0, r1 = albedo_renders(data, None)
        a0, s = r0.double().flatten(1), ((r1.double() - r0.double()) / (w1 - w0)).flatten(1)
        y = real - a0
        w = (s * y).sum(1) / (s * s).sum(1).clamp_min(1e-12)
        rss.append(((y - w[:, None] * s) ** 2).sum(1).numpy())
        a0s.append(a0), ss.append(s)
    rss = np.stack(rss)  # (L, N)
    pick = np.zeros(n, int)
    for v in set(vids):
        idx = [i for i in range(n) if vids[i] == v]
        pick[idx] = int(np.argmin(rss[:, idx].sum(1)))
    out = {}
    for tag, choice in (("", np.zeros(n, int)), ("E", pick)):
        LIGHT[0] = torch.tensor(np.stack([GRID[j] for j in choice]), dtype=torch.float32)
        a0 = torch.stack([a0s[j][i] for i, j in enumerate(choice)])
        s = torch.stack([ss[j][i] for i, j in enumerate(choice)])
        ext = S.extension_values(data, "specular", {"specular_ks": 1.0, "specular_shininess": 80.0})
        h = render_with(data, ext, w_d=torch.full((n,), w0), clamp=False).double().flatten(1) - a0
        out[tag] = (s, h, real - a0)
    LIGHT[0] = None
    (s, h, y), (sE, hE, yE) = out[""], out["E"]
    X = torch.stack([s, h], -1)
    XE = torch.stack([sE, hE], -1)
    G = np.zeros((n, 4, 4))
    b = np.zeros((n, 4))
    G[:, :2, :2] = torch.einsum("npk,npl->nkl", X, X).numpy()
    G[:, 2:, 2:] = torch.einsum("npk,npl->nkl", XE, XE).numpy()
    b[:, :2] = torch.einsum("npk,np->nk", X, y).numpy()
    b[:, 2:] = torch.einsum("npk,np->nk", XE, yE).numpy()
    tilt = [math.degrees(math.acos(min(1.0, float(np.dot(GRID[j], MODEL_LIGHT))))) for j in pick]
    return {"G": G, "b": b, "yy": (y * y).sum(1).numpy(), "yyE": (yE * yE).sum(1).numpy(), "npix": y.shape[1],
            "tilt_deg": np.array(tilt), **specular_truth(seeds, case)}


def main() -> int:
    return run_cases(case_gram, "cols", COLS)


if __name__ == "__main__":
    sys.exit(main())
