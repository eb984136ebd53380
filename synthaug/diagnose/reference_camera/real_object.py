"""The REAL object the reference camera films: the built-in quadcopter with its rotor parts, or a given
mesh, optionally deformed (:func:`perturb_mesh`) so that it differs from the fit's coarse model.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np


def quadcopter_parts(**kwargs: Any):
    """The built-in quadcopter (normalised) and a boolean mask of its rotor faces.

    Rotors are found as the connected components that are thin discs (height
    < 1.5 % of the model, span > 20 %), so the mask follows
    :func:`~synthaug.render.mesh.make_quadcopter` whatever its face order.

    Returns:
        (mesh, rotor_faces) with rotor_faces a (F,) bool array; 4 discs.
    """
    import trimesh

    from synthaug.render.mesh import make_quadcopter

    mesh = make_quadcopter(**kwargs)
    groups = trimesh.graph.connected_components(mesh.face_adjacency, nodes=np.arange(len(mesh.faces)))
    mask = np.zeros(len(mesh.faces), bool)
    n_rotors = 0
    for faces in groups:
        faces = np.asarray(faces)
        pts = mesh.vertices[np.unique(mesh.faces[faces])]
        ext = pts.max(0) - pts.min(0)
        if ext[2] < 0.015 and min(ext[0], ext[1]) > 0.2:
            mask[faces] = True
            n_rotors += 1
    if n_rotors != 4:
        raise RuntimeError(f"expected 4 rotor discs in the quadcopter, found {n_rotors}")
    return mesh, mask


def perturb_mesh(mesh: Any, amount: float, *, seed: int = 0):
    """A smoothly deformed copy of ``mesh`` (the real object ≠ the coarse model).

    Every vertex moves by ``amount`` × (unit-size mesh) × a smooth random field
    (three random sinusoids of the position, 1-3 cycles per unit), so parts
    bend, swell and shift coherently. Faces are kept (same face order).

    Example:
        >>> from synthaug.render.mesh import make_quadcopter
        >>> m = make_quadcopter()
        >>> p = perturb_mesh(m, 0.05, seed=1)
        >>> p.faces.shape == m.faces.shape, 0 < float(abs(p.vertices - m.vertices).max()) < 0.2
        (True, True)
    """
    import trimesh

    if not 0 <= amount <= 0.5:
        raise ValueError(f"mesh_perturbation must be in [0, 0.5], got {amount}")
    rng = np.random.default_rng(seed)
    v = np.asarray(mesh.vertices, np.float64)
    disp = np.zeros_like(v)
    for _ in range(3):
        freq = rng.normal(size=3)
        freq *= rng.uniform(1.0, 3.0) * 2 * np.pi / np.linalg.norm(freq)
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        disp += np.sin(v @ freq + rng.uniform(0, 2 * np.pi))[:, None] * direction / math.sqrt(3)
    return trimesh.Trimesh(vertices=v + amount * disp, faces=np.asarray(mesh.faces), process=False)


def _pinned(mesh: Any, lo: np.ndarray, hi: np.ndarray):
    """``mesh`` plus two sub-pixel triangles at the corners ``lo``/``hi``.

    Normalisation (centre and scale of the bounding box) then equals that of the
    mesh whose bounds these are, so the two render at the same place and size.
    """
    import trimesh

    eps = 1e-5
    tri = np.array([[0, 0, 0], [eps, 0, 0], [0, eps, 0]], np.float64)
    v = np.concatenate([mesh.vertices, lo + tri, hi - tri])
    n = len(mesh.vertices)
    f = np.concatenate([mesh.faces, [[n, n + 1, n + 2], [n + 3, n + 5, n + 4]]])
    return trimesh.Trimesh(vertices=v, faces=f, process=False)


def real_object(mesh: Any, perturbation: float, seed: int, *, rotor_scale: float = 1.0,
                 sections: int = 16) -> tuple[Any, Any | None, str]:
    """(full mesh, mesh without rotors or None, description). ``rotor_scale`` and ``sections`` change the
    built-in quadcopter's propeller radius and cylinder sections (the real object is not the model)."""
    from synthaug.render.mesh import load_mesh, normalize_mesh

    if isinstance(mesh, str) and mesh == "quadcopter":
        if rotor_scale == 1.0 and sections == 16:
            full, rotor = quadcopter_parts()
            desc = "quadcopter"
        else:
            full, rotor = quadcopter_parts(rotor_radius=0.17 * rotor_scale, sections=int(sections))
            desc = f"quadcopter (rotors x{rotor_scale:.3g}, {int(sections)} sections)"
    else:
        full, rotor = load_mesh(mesh), None
        desc = str(mesh) if isinstance(mesh, (str, os.PathLike)) else "<Trimesh>"
    if perturbation > 0:
        full = perturb_mesh(full, perturbation, seed=seed)
        desc += f" perturbed {perturbation:g} (seed {seed})"
    full = normalize_mesh(full)
    if rotor is None:
        return full, None, desc
    import trimesh

    body = trimesh.Trimesh(vertices=full.vertices, faces=full.faces[~rotor], process=False)
    body.remove_unreferenced_vertices()
    return full, _pinned(body, full.bounds[0], full.bounds[1]), desc
