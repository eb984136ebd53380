"""What a per-seed fit depends on (:func:`fit_inputs`), and which finished parts of an earlier run may be reused.

Every part records a fingerprint of its inputs: the seed set's content, the mesh, every
:class:`~synthaug.fit.config.FitConfig` option, the synthaug version, the optimiser's implementation, and a caller-given distance's state
(:func:`object_digest`). A rerun reuses a part only when its fingerprint is the current one, and recomputes the
others with a warning naming what changed (:func:`what_changed`: another ``--distance``, ``--budget``, seed set...).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from pathlib import Path
from typing import Any

import numpy as np
import torch

from synthaug._io import digest, sha256_file
from synthaug.fit.config import FitConfig, _cfg_json
from synthaug.params import atomic_write_text

log = logging.getLogger("synthaug.fit")


def _hash_object(h: Any, x: Any, depth: int = 0) -> None:
    """Feed a deterministic description of ``x`` (tensors and arrays by value) into the hash ``h``."""
    if isinstance(x, torch.nn.Module):  # parameters, buffers, submodules and plain attributes (learners...)
        h.update(f"module:{type(x).__module__}.{type(x).__qualname__}".encode())
        _hash_object(h, {k: v for k, v in vars(x).items() if "hook" not in k}, depth + 1)
        return
    if isinstance(x, torch.Tensor):
        t = x.detach().cpu().contiguous()
        h.update(f"tensor:{t.dtype}:{tuple(t.shape)}".encode())
        h.update(t.view(torch.uint8).numpy().tobytes() if t.numel() else b"")
        return
    if isinstance(x, np.ndarray):
        a = np.ascontiguousarray(x)
        h.update(f"array:{a.dtype}:{a.shape}".encode())
        if a.dtype != object:
            h.update(a.tobytes())
            return
        x = a.tolist()
    if x is None or isinstance(x, (bool, int, float, str, bytes)):
        h.update(repr(x).encode())
    elif isinstance(x, dict):
        h.update(b"{")
        for k in sorted(x, key=str):
            h.update(str(k).encode())
            _hash_object(h, x[k], depth + 1)
        h.update(b"}")
    elif isinstance(x, (list, tuple, set, frozenset)):
        h.update(b"[")
        for v in (sorted(x, key=repr) if isinstance(x, (set, frozenset)) else x):
            _hash_object(h, v, depth + 1)
        h.update(b"]")
    elif callable(x) and hasattr(x, "__qualname__") and not hasattr(x, "__dict__"):
        h.update(f"fn:{getattr(x, '__module__', '')}.{x.__qualname__}".encode())
    else:
        h.update(f"obj:{type(x).__module__}.{type(x).__qualname__}".encode())
        if depth < 24 and hasattr(x, "__dict__"):
            _hash_object(h, {k: v for k, v in vars(x).items() if not k.startswith("__")}, depth + 1)


def object_digest(x: Any) -> str:
    """SHA-256 of an object's state (a prebuilt distance: its networks' weights, its arrays, its options)."""
    h = hashlib.sha256()
    _hash_object(h, x)
    return h.hexdigest()[:20]


def seedset_digest(seeds_path: str | os.PathLike) -> str:
    """SHA-256 of a seed set's header and arrays (``seedset.json`` + ``arrays.npz``): what a fit reads."""
    from synthaug.data.seedset import ARRAYS, HEADER

    root = Path(seeds_path)
    return digest({name: sha256_file(root / name) for name in (HEADER, ARRAYS) if (root / name).is_file()},
                  length=64)


def mesh_digest(mesh: Any) -> str:
    """SHA-256 of a mesh file's bytes, ``builtin:<name>`` for a built-in mesh, of the arrays for a Trimesh."""
    from synthaug.render.mesh import BUILTIN_MESHES

    if isinstance(mesh, str) and mesh in BUILTIN_MESHES:  # as load_mesh: the name wins over a file
        return f"builtin:{mesh}"
    if isinstance(mesh, (str, os.PathLike)):
        return sha256_file(mesh)
    return object_digest({"vertices": np.asarray(mesh.vertices), "faces": np.asarray(mesh.faces)})


def fit_inputs(seeds_path: str | os.PathLike, mesh: Any, cfg: FitConfig, distance: Any = None) -> dict[str, Any]:
    """Everything a per-seed fit depends on: the seed set's content, the mesh, every option, the synthaug
    version, the optimiser's implementation, and the state of a caller-given distance (None: built from ``cfg`` and the seeds)."""
    from synthaug import __version__
    from synthaug.fit.optimizers import get_optimizer

    out = {"seedset_sha256": seedset_digest(seeds_path), "mesh_sha256": mesh_digest(mesh), "config": _cfg_json(cfg),
           "synthaug_version": __version__, "optimizer": get_optimizer(cfg.optimizer).implementation()}
    if distance is not None:
        out["distance_object"] = object_digest(distance)
    return out


_INPUT_NAMES = {"seedset_sha256": "the seed set's content", "mesh_sha256": "the mesh",
                "synthaug_version": "the synthaug version", "optimizer": "the optimiser's implementation",
                "distance_object": "the given distance object"}


def what_changed(old: dict[str, Any] | None, new: dict[str, Any]) -> str:
    """A short human description of how two :func:`fit_inputs` differ (``""`` when they are equal)."""
    if not isinstance(old, dict):
        return "it records no fingerprint (written by an older synthaug)"
    diffs = []
    oc, nc = old.get("config", {}) or {}, new.get("config", {}) or {}
    for k in sorted(set(oc) | set(nc)):
        if oc.get(k) != nc.get(k):
            diffs.append(f"{k} {json.dumps(oc.get(k), default=str)} -> {json.dumps(nc.get(k), default=str)}")
    for k in ("seedset_sha256", "mesh_sha256", "synthaug_version", "optimizer", "distance_object"):
        if old.get(k) != new.get(k):
            what = _INPUT_NAMES[k]
            if k in ("synthaug_version", "optimizer"):
                what += f" {old.get(k)} -> {new.get(k)}"
            diffs.append(what)
    return ", ".join(diffs)


def _read_part(path: Path) -> dict[str, Any] | None:
    try:
        doc = json.loads(path.read_text())
        return doc if isinstance(doc, dict) and "theta" in doc else None
    except (OSError, ValueError):
        return None


def _check_parts(parts: Path, fingerprint: dict[str, Any]) -> set[int]:
    """The indices of the parts that may be reused; the others (other inputs, unreadable) are removed, with a
    warning naming what changed."""
    fp = fingerprint["digest"]
    config = parts / "config.json"
    if config.is_file():
        try:
            old = json.loads(config.read_text())
        except (OSError, ValueError):
            old = None
        old_inputs = old.get("inputs") if isinstance(old, dict) else None
        if not isinstance(old, dict) or old.get("fingerprint") != fp:
            why = what_changed(old_inputs, fingerprint["inputs"]) or "its config file is unreadable"
            log.warning("synthaug fit: %s holds an interrupted run with other inputs (%s)", parts, why)
    done: set[int] = set()
    stale: dict[str, list[int]] = {}
    for p in sorted(parts.glob("seed_*.json")):
        try:
            i = int(p.stem.split("_")[1])
        except (IndexError, ValueError):
            continue
        doc = _read_part(p)
        if doc is not None and doc.get("fingerprint") == fp:
            done.add(i)
            continue
        why = "unreadable" if doc is None else what_changed(doc.get("inputs"), fingerprint["inputs"])
        stale.setdefault(why or "another fingerprint", []).append(i)
        p.unlink(missing_ok=True)
    for why, idx in stale.items():
        shown = ", ".join(map(str, idx[:8])) + (", ..." if len(idx) > 8 else "")
        log.warning("synthaug fit: recomputing %d finished seed(s) [%s] of an earlier run in %s: %s",
                    len(idx), shown, parts, why)
    atomic_write_text(config, json.dumps({"fingerprint": fp, "inputs": fingerprint["inputs"]}, indent=1,
                                         default=str))
    return done
