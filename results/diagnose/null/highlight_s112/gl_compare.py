"""Issue 20, stop 112: gram_light.py's oracle (the template and the diffuse shading at each video's true light) against
the library's template at the model's light, judged as stop 111's compare.py judges (the library's pooling, floor
rule over the 44 calibration cases and test). Per-set counts in the order of the arguments' specular cases.

    PYTHONPATH=. python results/diagnose/null/highlight_s112/gl_compare.py outputs/s112_gl_calib.npz \
        outputs/s112_gl_clean.npz outputs/s112_gl_spec.npz
"""
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from table import HEADER, row  # noqa: E402

from compare import pooled  # noqa: E402  (stop 111's, on the path table.py puts it)

MODELS = {"s,h80 at the model's light (library)": ([0, 1], "yy"), "s,h45 at the model's light": ([0, 2], "yy"),
          "sL,h80L at the video's true light": ([3, 4], "yyL"), "sL,h45L at the video's true light": ([3, 5], "yyL")}


def per_seed(case, idx, yy_key):
    G, b, yy = case["G"][:, idx][:, :, idx], case["b"][:, idx], case[yy_key]
    ks, vs = [], []
    for i in range(len(b)):
        if G[i][1, 1] < 1e-8 or np.linalg.cond(G[i]) > 1e10:
            continue
        gi = np.linalg.inv(G[i])
        beta = gi @ b[i]
        ks.append(beta[1])
        vs.append(max((yy[i] - b[i] @ beta) / (int(case["npix"]) - 2), 1e-12) * gi[1, 1])
    return np.array(ks), np.array(vs)


def load_cases(paths, keys):
    """The cached cases of several gram_light.py / light_grid.py outputs: their name and the arrays ``keys``."""
    cases = []
    for p in paths:
        d = np.load(p)
        cases += [{"name": str(c), **{k: d[f"{i}:{k}"] for k in keys}} for i, c in enumerate(d["cases"])]
    return cases


def print_rows(cases, models, default_key="specular/"):
    """The table (table.py) of ``models`` ({label: (two column indices, the y'y key)}) over ``cases``."""
    print(HEADER)
    for name, (idx, yk) in models.items():
        res = {}
        for c in cases:
            k, v = per_seed(c, idx, yk)
            res[c["name"]] = (*pooled(k, v, "mean"), len(k))
        print(row(name, res, default_key=default_key))


def main():
    print_rows(load_cases(sys.argv[1:], ("G", "b", "yy", "yyL", "npix")), MODELS, default_key="specular_default/")


if __name__ == "__main__":
    main()
