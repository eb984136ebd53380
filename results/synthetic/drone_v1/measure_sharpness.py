"""Issue 16: how sharp the synthetic positives are against the real seed patches (a factor HOG's normalisation keeps).

Sharpness of a patch = mean |horizontal| + |vertical| pixel difference over its central 20 x 20 px, divided by the
central region's intensity range (contrast-free: a dim and a bright drone of the same shape score alike). Median over
the real seed patches, over 5 synthetic training samples per seed (uniform poses, as training uses them), and over
each fit's own renders S(Θ_i, B_i), for the d_HOG fits (σ_n fitted / measured) and the d_CNN fits.

    OMP_NUM_THREADS=1 PYTHONPATH=. python results/synthetic/drone_v1/measure_sharpness.py   # from the repository root
"""

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.diagnose.gap import training_samples
from synthaug.fit.render_fit import render_fitted

MESH = "../shared/data/meshes/quadcopter.glb"


def sharpness(x: torch.Tensor) -> np.ndarray:
    c = x[..., 10:30, 10:30]
    gx, gy = c[..., :, 1:] - c[..., :, :-1], c[..., 1:, :] - c[..., :-1, :]
    rng = (c.flatten(1).max(1).values - c.flatten(1).min(1).values).clamp_min(1e-3)
    return ((gx.abs().flatten(1).mean(1) + gy.abs().flatten(1).mean(1)) / rng).numpy()


def main() -> None:
    torch.set_num_threads(1)
    for s in (0, 1, 2):
        ss = SeedSet.load(f"data/runs/ingest_drone_seed{s}/seedsets/drone_100")
        real = torch.as_tensor(np.asarray(ss.patches)).float().div(255).unsqueeze(1)
        row = [f"seed set {s}: real {np.median(sharpness(real)):.4f}"]
        for fit in ("hog", "hog_measured", "cnn"):
            f = f"data/runs/fits/drone_100_seed{s}_{fit}.json"
            syn, _ = training_samples(ss, MESH, f, 5 * len(ss), seed=s + 2)
            fr = render_fitted(ss, f, MESH)[1].clamp(0, 1)
            row.append(f"{fit}: samples {np.median(sharpness(syn)):.4f} fitted renders {np.median(sharpness(fr)):.4f}")
        print(" | ".join(row), flush=True)


if __name__ == "__main__":
    main()
