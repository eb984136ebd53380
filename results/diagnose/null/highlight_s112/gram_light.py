"""Issue 20, stop 112: the highlight's normal equations with the template and the albedo slope rendered at each
video's TRUE light (an oracle: the seed records' nuisance light), beside the model's light — what a light-following
template could gain at best, once the reference camera lights a hidden highlight by its video's light (stop 112).

Columns: ``s``, ``h80``, ``h45`` (the model's light, as the library) and ``sL``, ``h80L``, ``h45L`` (each seed's video
light; the diffuse shading too).

    PYTHONPATH=. python results/diagnose/null/highlight_s112/gram_light.py OUT.npz CASE_DIR...
"""
import pathlib
import sys

import numpy as np
import torch

import synthaug.effects.pipeline as pipeline

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from gram import load_case, run_cases, slope_and_templates, specular_truth  # noqa: E402  (stop 111's)

COLS = ["s", "h80", "h45", "sL", "h80L", "h45L"]
_simulate = pipeline.simulate
LIGHT: list = [None]


def _lit(*a, extras=None, **k):
    extras = dict(extras or {})
    if LIGHT[0] is not None:
        extras["light_dir"] = LIGHT[0]
    return _simulate(*a, extras=extras, **k)


pipeline.simulate = _lit


def case_gram(case: str) -> dict:
    seeds, data = load_case(case)
    n = len(data)
    LIGHT[0] = None
    a0, cols = slope_and_templates(data, (80.0, 45.0))
    light = [r["truth"].get("nuisance", {}).get("light_dir", (0.0, 0.5, 0.8660254)) for r in seeds.records]
    LIGHT[0] = torch.tensor(light, dtype=torch.float32)
    a0L, colsL = slope_and_templates(data, (80.0, 45.0))
    LIGHT[0] = None
    y = (data.real.double() - a0).flatten(1)
    # the light-following model's columns are taken against the same a0 (the model's render at w_d 0.2): add the
    # difference of the two renders at w_d 0.2 to the slope's span by fitting y - (a0L - a0) instead
    yL = (data.real.double() - a0L).flatten(1)
    X = torch.stack([c.flatten(1) for c in cols], -1)
    XL = torch.stack([c.flatten(1) for c in colsL], -1)
    G = torch.einsum("npk,npl->nkl", X, X).numpy()
    b = torch.einsum("npk,np->nk", X, y).numpy()
    GL = torch.einsum("npk,npl->nkl", XL, XL).numpy()
    bL = torch.einsum("npk,np->nk", XL, yL).numpy()
    Gf, bf = np.zeros((n, 6, 6)), np.zeros((n, 6))
    Gf[:, :3, :3], Gf[:, 3:, 3:], bf[:, :3], bf[:, 3:] = G, GL, b, bL  # two separate models in one block matrix
    yy = (y * y).sum(1).numpy()
    yyL = (yL * yL).sum(1).numpy()
    return {"G": Gf, "b": bf, "yy": yy, "yyL": yyL, "npix": y.shape[1], **specular_truth(seeds, case)}


def main() -> int:
    return run_cases(case_gram, "cols", COLS)


if __name__ == "__main__":
    sys.exit(main())
