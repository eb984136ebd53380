"""Issue 20, stop 112: per-seed normal equations of the highlight estimator with regressors for the clean material's
shading nuisances, cached for offline comparison (stop 111's compare.py solves them).

Stop 111 measured that the clean cases' own spread of the highlight amplitude k (case-level, not seeds' noise) sets
the specular floor. The nuisances that move the diffuse shading of the real object away from the model's (each video's
light tilted by up to 40 degrees, smooth normals, another ambient) are linear (to first order) in a few renders of the
model; this script adds them as columns beside stop 111's:

- ``s``: the albedo slope; ``h80``, ``h45``: the specular template (ks 1) at exponents 80 and 45;
- ``lx``, ``ly``: the diffuse shading's derivative in the light's direction (the model's normals rotated by ±δ about
  the camera's x and y axes: a rotated light), at the fitted w_d;
- ``sm``: smooth shading (the normal map blurred by 1.3 frame px inside the object, renormalised) minus the model's;
- ``amb``: the object at uniform full light (normals toward the light) minus the model's: with ``s``, an ambient change;
- ``gx``, ``gy``: the object layer's shift derivatives (as stop 111's).

    PYTHONPATH=. python results/diagnose/null/highlight_s112/gram.py OUT.npz CASE_DIR...
"""
import dataclasses
import math
import pathlib
import sys

import torch

from synthaug.diagnose.diagnosis_data import render_with
from synthaug.diagnose.nuisances import MODEL_LIGHT
from synthaug.effects.functional import gaussian_blur_fft

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from gram import (load_case, run_cases, shift_derivatives, slope_and_templates,  # noqa: E402  (stop 111's)
                  specular_truth)

COLS = ["s", "h80", "h45", "lx", "ly", "sm", "amb", "gx", "gy"]
DELTA = 0.1  # rad, the light's central difference
SMOOTH_FRAME_PX = 1.3


def rotated(normals, axis, angle):
    c, s = math.cos(angle), math.sin(angle)
    n = normals.clone()
    i, j = (1, 2) if axis == "x" else (0, 2)
    n[:, i], n[:, j] = c * normals[:, i] - s * normals[:, j], s * normals[:, i] + c * normals[:, j]
    return n


def smoothed(normals, coverage, sigma):
    """smooth_normals with one σ (patch px) per seed."""
    pad = int(math.ceil(3 * float(sigma.max()))) + 2
    w = (coverage > 0).to(normals.dtype)
    num = gaussian_blur_fft(normals * w, sigma.to(normals.dtype), pad=pad, border="constant")
    den = gaussian_blur_fft(w, sigma.to(normals.dtype), pad=pad, border="constant").clamp_min(1e-6)
    n = num / den
    n = n / n.norm(dim=1, keepdim=True).clamp_min(1e-6)
    return torch.where(w > 0, n, torch.zeros_like(n))


def case_gram(case: str) -> dict:
    seeds, data = load_case(case)
    a0, cols = slope_and_templates(data, (80.0, 45.0))
    r = render_with(data, None, clamp=False).double()  # at the fitted w_d
    with_normals = lambda nrm: render_with(dataclasses.replace(data, normals=nrm), None, clamp=False).double()  # noqa
    for axis in ("x", "y"):
        cols.append((with_normals(rotated(data.normals, axis, DELTA))
                     - with_normals(rotated(data.normals, axis, -DELTA))) / (2 * DELTA))
    sig = (SMOOTH_FRAME_PX / data.frame_scale.double()).float()
    cols.append(with_normals(smoothed(data.normals, data.coverage, sig)) - r)
    light = torch.tensor(MODEL_LIGHT, dtype=data.normals.dtype).reshape(1, 3, 1, 1)
    cols.append(with_normals(light * (data.coverage > 0).to(data.normals.dtype)) - r)
    cols += list(shift_derivatives(data, r))
    X = torch.stack([c.flatten(1) for c in cols], -1)  # (N, P, K)
    y = (data.real.double() - a0).flatten(1)
    G = torch.einsum("npk,npl->nkl", X, X).numpy()
    b = torch.einsum("npk,np->nk", X, y).numpy()
    yy = (y * y).sum(1).numpy()
    return {"G": G, "b": b, "yy": yy, "npix": y.shape[1], **specular_truth(seeds, case)}


def main() -> int:
    return run_cases(case_gram, "cols", COLS, echo=lambda g: len(g["yy"]))


if __name__ == "__main__":
    sys.exit(main())
