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
