"""Issue 20, stop 112: the highlight amplitude with the shading nuisances' regressors shared where the nuisance is
(each video's light: ``lx``, ``ly`` one pair per video; the material's ambient and smooth normals: ``amb``, ``sm`` one
value per case), the albedo slope and the highlight per seed — one joint weighted least squares per case over the
cached per-seed normal equations (gram.py), then the library's pooling, floor rule and test (stop 111's compare.py).

A per-seed light derivative absorbs a highlight (the lobe sits on the facets the light's tilt brightens); one light
per video cannot follow each pose's highlight.

    PYTHONPATH=. python results/diagnose/null/highlight_s112/shared.py outputs/s112_gram_calib_spec.npz \
        outputs/s112_gram_clean.npz
"""
import json
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from table import HEADER, row  # noqa: E402

from compare import load_all, pooled  # noqa: E402  (stop 111's, on the path table.py puts it)


def videos(case):
    recs = json.loads((pathlib.Path(case) / "seeds" / "seedset.json").read_text())["records"]
    return [r["video"] for r in recs]


def joint_k(case, ci, seed_cols, video_cols, case_cols, stat="h80"):
    """Per-seed k (and its variance) of the joint fit: seed_cols per seed, video_cols per video, case_cols per case."""
    vids = videos(case["name"])
    uv = sorted(set(vids))
    n, ns, nv, nc = len(vids), len(seed_cols), len(video_cols), len(case_cols)
    cols = seed_cols + video_cols + case_cols
    idx = [ci[c] for c in cols]
    G, b, yy, npix = case["G"][:, idx][:, :, idx], case["b"][:, idx], case["yy"], int(case["npix"])
    P = n * ns + len(uv) * nv + nc

    def place(i):  # the global index of seed i's columns
        v = uv.index(vids[i])
        return (list(range(i * ns, (i + 1) * ns)) + list(range(n * ns + v * nv, n * ns + (v + 1) * nv))
                + list(range(n * ns + len(uv) * nv, P)))

    keep = [i for i in range(n) if G[i][1, 1] > 1e-8]
    wts = np.ones(n)
    for _ in range(2):  # unweighted, then each seed weighted by 1 / its residual variance
        A, r = np.zeros((P, P)), np.zeros(P)
        for i in keep:
            p = place(i)
            A[np.ix_(p, p)] += G[i] * wts[i]
            r[p] += b[i] * wts[i]
        for i in range(n):
            if i not in keep:
                A[i * ns:(i + 1) * ns, i * ns:(i + 1) * ns] += np.eye(ns)  # unused seeds: a dummy identity
        Ai = np.linalg.pinv(A)
        th = Ai @ r
        rss = np.array([yy[i] - 2 * b[i] @ th[place(i)] + th[place(i)] @ G[i] @ th[place(i)] for i in range(n)])
        dof = npix - ns - (nv * len(uv) + nc) / n
        wts = 1.0 / np.maximum(rss / dof, 1e-12)
    j = seed_cols.index(stat)
    k = np.array([th[i * ns + j] for i in keep])
    v = np.array([Ai[i * ns + j, i * ns + j] for i in keep])
    return k, v


MODELS = {
    "per seed s,h80 (library)": (["s", "h80"], [], []),
    "case: amb,sm": (["s", "h80"], [], ["amb", "sm"]),
    "case: amb": (["s", "h80"], [], ["amb"]),
    "video: lx,ly": (["s", "h80"], ["lx", "ly"], []),
    "video: lx,ly; case: amb,sm": (["s", "h80"], ["lx", "ly"], ["amb", "sm"]),
    "video: lx,ly,amb,sm": (["s", "h80"], ["lx", "ly", "amb", "sm"], []),
    "h45 per seed": (["s", "h45"], [], []),
    "h45; case: amb,sm": (["s", "h45"], [], ["amb", "sm"]),
    "h45; video: lx,ly; case: amb,sm": (["s", "h45"], ["lx", "ly"], ["amb", "sm"]),
    "h45; per seed amb,sm": (["s", "h45", "amb", "sm"], [], []),
    "h45; per seed amb,sm; video lx,ly": (["s", "h45", "amb", "sm"], ["lx", "ly"], []),
}


def main():
    ci, cases = load_all(sys.argv[1:])
    print(HEADER)
    for name, (sc, vc, cc) in MODELS.items():
        res = {}
        for case in cases:
            k, v = joint_k(case, ci, sc, vc, cc, stat=sc[1])
            res[case["name"]] = (*pooled(k, v, "mean"), len(k))
        print(row(name, res), flush=True)


if __name__ == "__main__":
    main()
