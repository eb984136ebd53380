"""Mesh loading and normalisation, and the built-in coarse quadcopter.

Every mesh the renderer sees is one :class:`trimesh.Trimesh`, centred on its
bounding-box centre and scaled so that the longest bounding-box side is 1
("unit size"); a pose then places it in a patch at a fixed object scale.

Example:
    >>> m = make_quadcopter()
    >>> [round(float(x), 6) for x in m.extents.max(keepdims=True)]
    [1.0]
    >>> bool(abs(m.bounds.mean(0)).max() < 1e-9)
    True
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np
import trimesh

SUPPORTED_SUFFIXES = (".obj", ".ply", ".stl", ".glb", ".gltf", ".off")
BUILTIN_MESHES = ("quadcopter",)


def normalize_mesh(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """A copy centred on its bounding-box centre with longest side 1."""
    if len(mesh.faces) == 0:
        raise ValueError("mesh has no faces")
    out = mesh.copy()
    extent = float(out.extents.max())
    if not np.isfinite(extent) or extent <= 0:
        raise ValueError(f"mesh has a degenerate extent {extent}")
    out.apply_translation(-out.bounds.mean(axis=0))
    out.apply_scale(1.0 / extent)
    return out


def load_mesh(source: str | os.PathLike | trimesh.Trimesh, *, normalize: bool = True) -> trimesh.Trimesh:
    """Load OBJ/PLY/STL/GLB/GLTF/OFF (or ``"quadcopter"``), flatten scenes, normalise.

    Args:
        source: a path, a :class:`trimesh.Trimesh`, or the name of a built-in mesh.
        normalize: centre and scale to unit size (see :func:`normalize_mesh`).

    Returns:
        a single triangle mesh.

    Raises:
        FileNotFoundError: the file does not exist.
        ValueError: the file cannot be read, holds no triangles, or is not a mesh;
            the message names the file.
    """
    if isinstance(source, trimesh.Trimesh):
        mesh = source
        name = "<Trimesh>"
    elif isinstance(source, str) and source in BUILTIN_MESHES:
        return make_quadcopter()
    else:
        path = Path(source)
        name = str(path)
        if not path.exists():
            raise FileNotFoundError(f"mesh file not found: {path}")
        if path.is_dir():
            raise ValueError(f"mesh path is a directory, not a file: {path}")
        if path.stat().st_size == 0:
            raise ValueError(f"mesh file is empty: {path}")
        try:
            loaded = trimesh.load(path, process=False)
        except Exception as e:  # trimesh raises many types for broken files
            raise ValueError(f"cannot read mesh file {path}: {type(e).__name__}: {e}") from None
        if isinstance(loaded, trimesh.Scene):
            meshes = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh) and len(g.faces)]
            if not meshes:
                raise ValueError(f"mesh file {path} holds no triangle geometry")
            mesh = trimesh.util.concatenate(meshes)
        elif isinstance(loaded, trimesh.Trimesh):
            mesh = loaded
        else:
            raise ValueError(f"mesh file {path} holds a {type(loaded).__name__}, not a triangle mesh")
    if len(mesh.faces) == 0 or len(mesh.vertices) == 0:
        raise ValueError(f"mesh {name} has no triangles")
    if not np.isfinite(mesh.vertices).all():
        raise ValueError(f"mesh {name} has non-finite vertices")
    mesh = trimesh.Trimesh(vertices=np.asarray(mesh.vertices, dtype=np.float64),
                           faces=np.asarray(mesh.faces, dtype=np.int64), process=False)
    return normalize_mesh(mesh) if normalize else mesh


def mesh_parts(mesh: trimesh.Trimesh) -> np.ndarray:
    """The part of every vertex, ``(V,)`` int: the connected pieces of the mesh once coincident vertices are merged
    (a body, an arm, a rotor blade, a wing...; pieces that share a vertex are one part); a vertex no face uses is
    in no part (-1)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    merged = mesh.copy()
    merged.merge_vertices()  # keeps the face order: merged.faces[i, j] is where mesh.faces[i, j] went
    f = np.asarray(merged.faces)
    a = np.concatenate([f[:, 0], f[:, 1], f[:, 2]])
    b = np.concatenate([f[:, 1], f[:, 2], f[:, 0]])
    n = len(merged.vertices)
    _, labels = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)
    out = np.full(len(mesh.vertices), -1, dtype=np.int64)
    out[np.asarray(mesh.faces).ravel()] = labels[f.ravel()]
    return out


def shape_variants(mesh: str | os.PathLike | trimesh.Trimesh, n: int, *, strength: float = 0.3,
                   seed: int = 0) -> list[trimesh.Trimesh]:
    """``n`` variations of the shape of a coarse mesh, for domain randomisation of the silhouette.

    Variant 0 is the mesh itself. Each other variant stretches the whole mesh along each of its axes and scales
    every part (:func:`mesh_parts`: a connected component, e.g. an arm, a motor, a rotor blade, a wing) about
    its own centre, each factor drawn log-uniformly in ``[1 / (1 + strength), 1 + strength]``: arm length, rotor
    size and body proportions vary around the model while the parts stay where the model puts them. Every
    variant is normalised (:func:`normalize_mesh`), so a fitted object scale means the same longest side.

    Args:
        mesh: a path, built-in name or trimesh (normalised on load).
        n: number of variants (>= 1).
        strength: the largest relative change of one factor (> 0; 0.3: ±30 %).
        seed: seed of the draws (the variants are a pure function of the mesh, ``n``, ``strength``, ``seed``).

    Example:
        >>> vs = shape_variants("quadcopter", 3, strength=0.3, seed=0)
        >>> len(vs), bool((vs[0].vertices == load_mesh("quadcopter").vertices).all())
        (3, True)
        >>> [round(float(v.extents.max()), 6) for v in vs]
        [1.0, 1.0, 1.0]
    """
    if int(n) != n or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n}")
    if not (np.isfinite(strength) and strength > 0):
        raise ValueError(f"strength must be > 0, got {strength}")
    base = load_mesh(mesh)
    parts = mesh_parts(base)
    ids = np.unique(parts[parts >= 0])
    n_parts = int(parts.max()) + 1
    rng = np.random.default_rng(seed)
    span = float(np.log1p(strength))
    out = [base]
    for _ in range(int(n) - 1):
        axis = np.exp(rng.uniform(-span, span, 3))
        part = np.exp(rng.uniform(-span, span, n_parts))
        v = np.asarray(base.vertices, np.float64) * axis
        for k in ids:
            sel = parts == k
            centre = (v[sel].min(0) + v[sel].max(0)) / 2
            v[sel] = centre + (v[sel] - centre) * part[k]
        out.append(normalize_mesh(trimesh.Trimesh(vertices=v, faces=base.faces, process=False)))
    return out


def mesh_fingerprint(mesh: trimesh.Trimesh) -> str:
    """Stable hash of the geometry (for on-disk caches)."""
    h = hashlib.sha1()
    h.update(np.ascontiguousarray(mesh.vertices, dtype=np.float32).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    return h.hexdigest()[:16]


def make_quadcopter(*, rotor_radius: float = 0.17, sections: int = 16) -> trimesh.Trimesh:
    """A coarse quadcopter from primitives: body, four arms, motors and rotor discs.

    The frame is z-up (rotor plane = xy); returned normalised to unit size.
    About 500 faces: a *coarse* model, as the paper uses.
    """
    parts: list[trimesh.Trimesh] = []
    parts.append(trimesh.creation.box(extents=(0.22, 0.22, 0.08)))
    parts.append(trimesh.creation.box(extents=(0.14, 0.10, 0.05),
                                      transform=trimesh.transformations.translation_matrix((0, 0, -0.065))))
    arm_len = 0.5
    for k in range(4):
        ang = np.pi / 4 + k * np.pi / 2
        c, s = np.cos(ang), np.sin(ang)
        rot = trimesh.transformations.rotation_matrix(ang, (0, 0, 1))
        arm = trimesh.creation.box(extents=(arm_len, 0.04, 0.03))
        arm.apply_transform(trimesh.transformations.translation_matrix((arm_len / 2 * c, arm_len / 2 * s, 0)) @ rot)
        parts.append(arm)
        tip = np.array([arm_len * c, arm_len * s, 0.0])
        motor = trimesh.creation.cylinder(radius=0.035, height=0.07, sections=sections)
        motor.apply_translation(tip + (0, 0, 0.02))
        parts.append(motor)
        rotor = trimesh.creation.cylinder(radius=rotor_radius, height=0.008, sections=2 * sections)
        rotor.apply_translation(tip + (0, 0, 0.06))
        parts.append(rotor)
        leg = trimesh.creation.box(extents=(0.02, 0.02, 0.1))
        leg.apply_translation(0.12 * np.array([c, s, 0]) + (0, 0, -0.08))
        parts.append(leg)
    mesh = trimesh.util.concatenate(parts)
    return normalize_mesh(trimesh.Trimesh(mesh.vertices, mesh.faces, process=False))
