"""Stop 64: how the fits of the two meshes differ, seed by seed, on the same seed sets (trains nothing).

    PYTHONPATH=. python results/synthetic/mesh_factor/theta.py [--seeds 0 1 2 3 4] [--out theta.md]

For each training seed's 100-seed set: the median of each capture parameter and of the fit's HOG distance, in the
``quadcopter.glb`` fit (``data/runs/fits/drone_100_seed{s}_hog.json``) and the built-in one
(``..._hog_builtin.json``), and the Wilcoxon signed-rank p of the paired per-seed differences (the same real seed
fitted twice).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.stats import wilcoxon

from synthaug.params import CaptureParams, fitted_object_scales

FIELDS = ("t_x", "t_y", "sigma_s", "sigma_u", "sigma_v", "alpha_m", "sigma_n", "w_d")


def columns(path: str | Path) -> dict[str, np.ndarray]:
    """Per-seed values of each field (first channel), the fit's distance and its object scale."""
    params, extra, _ = CaptureParams.load_with_extra(path)
    values = params.as_dict()
    out = {k: values[k].reshape(len(params), -1)[:, 0].double().numpy() for k in FIELDS}
    out["distance"] = np.array([e["distance"] for e in extra], float)
    out["object_scale"] = fitted_object_scales(extra).double().numpy()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--fits", default="data/runs/fits/drone_100_seed{seed}_hog{mesh}.json")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    keys = (*FIELDS, "distance", "object_scale")
    lines = ["| field | " + " | ".join(f"seed {s}: .glb / built-in (p)" for s in a.seeds) + " |",
             "|---|" + "---|" * len(a.seeds)]
    fits = {s: (columns(a.fits.format(seed=s, mesh="")), columns(a.fits.format(seed=s, mesh="_builtin")))
            for s in a.seeds}
    for k in keys:
        cells = []
        for s in a.seeds:
            g, b = fits[s][0][k], fits[s][1][k]
            p = wilcoxon(g, b).pvalue if np.any(g != b) else 1.0
            cells.append(f"{np.median(g):.3f} / {np.median(b):.3f} ({p:.2g})")
        lines.append(f"| {k} | " + " | ".join(cells) + " |")
    text = "\n".join(lines)
    print(text)
    if a.out:
        Path(a.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
