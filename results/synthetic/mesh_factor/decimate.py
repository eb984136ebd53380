"""Issue 16, stop 66: which part of the shared mesh costs HOG its synthetic gain, its detail or its proportions?

Writes ``quadcopter.glb`` decimated to the built-in quadcopter's face count (quadric error metric, trimesh's
``simplify_quadric_decimation``, backed by ``fast-simplification``; not a dependency of the library: ``pip install
-e ".[mesh]"`` for this script). The decimated mesh keeps the shared mesh's proportions (arms, rotors, legs where
they are) and loses its detail; the built-in quadcopter differs in both. It is written under ``data/`` (generated,
not committed: nothing from ``../shared`` goes into the repository).

Usage::

    PYTHONPATH=. python results/synthetic/mesh_factor/decimate.py ../shared/data/meshes/quadcopter.glb \
        data/meshes/quadcopter_glb_decimated.ply
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def main() -> int:
    import trimesh

    from synthaug.render.mesh import load_mesh

    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("out")
    ap.add_argument("--faces", type=int, default=None, help="target face count (default: the built-in quadcopter's)")
    ap.add_argument("--scale", type=float, nargs=3, default=None, metavar=("SX", "SY", "SZ"),
                    help="then stretch the decimated mesh along its axes (e.g. 1.24 1 1: the .glb's 0.81 x 1 "
                         "footprint made square, as the built-in quadcopter's)")
    a = ap.parse_args()
    src = trimesh.load(a.mesh, force="mesh")
    target = a.faces or len(load_mesh("quadcopter").faces)
    dec = src.simplify_quadric_decimation(face_count=target)
    # how far the decimated surface lies from the source's (in units of the source's longest side): each point
    # sampled on it against the nearest of 200,000 points sampled on the source (scipy's k-d tree)
    from scipy.spatial import cKDTree

    pts, _ = trimesh.sample.sample_surface(dec, 20000, seed=0)
    ref, _ = trimesh.sample.sample_surface(src, 200000, seed=1)
    dist, _ = cKDTree(ref).query(pts)
    scale = float(src.extents.max())
    if a.scale is not None:  # the stretch comes after the decimation's distance is measured
        dec.apply_scale(np.asarray(a.scale, np.float64))
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    dec.export(a.out)
    print(json.dumps({"source": a.mesh, "out": a.out, "faces": [len(src.faces), len(dec.faces)],
                      "vertices": [len(src.vertices), len(dec.vertices)],
                      "extents_source": np.round(src.extents / scale, 4).tolist(),
                      "extents_decimated": np.round(dec.extents / scale, 4).tolist(),
                      "scale": a.scale, "surface_distance_median": round(float(np.median(dist)) / scale, 5),
                      "surface_distance_p99": round(float(np.quantile(dist, 0.99)) / scale, 5)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
