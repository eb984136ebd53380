"""Stop 64: is the mesh factor the object noise the fit gives each mesh? Write a fit of one mesh with one capture
parameter taken, seed by seed, from a fit of the same seed set with another mesh.

    PYTHONPATH=. python results/synthetic/mesh_factor/transplant.py FIT FROM OUT [--field sigma_n]

FIT and FROM must fit the same seed set (the same seeds in the same order); OUT is FIT with ``--field`` of every row
replaced by FROM's. Everything else of FIT (poses, blurs, material, its mesh) is kept, so a detector trained from OUT
differs from one trained from FIT by that one parameter. OUT's metadata records what was replaced and from where.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np


def transplant(fit: dict, donor: dict, field: str) -> dict:
    """``fit`` with ``field`` of each row replaced by ``donor``'s row of the same seed index."""
    rows, drows = fit["rows"], donor["rows"]
    idx = [r["extra"]["seed_index"] for r in rows]
    if idx != [r["extra"]["seed_index"] for r in drows]:
        raise ValueError("the two fits do not hold the same seeds in the same order")
    if fit["metadata"].get("seeds") != donor["metadata"].get("seeds"):
        raise ValueError(f"the fits are of different seed sets: {fit['metadata'].get('seeds')!r} vs "
                         f"{donor['metadata'].get('seeds')!r}")
    if field not in rows[0]["theta"]:
        raise ValueError(f"no field {field!r} in the fit (fields: {sorted(rows[0]['theta'])})")
    # the JSON is copied, not read into CaptureParams and saved: that holds float32, which would round every other
    # field of the fit and so change more than the one parameter
    out = json.loads(json.dumps(fit))
    for r, d in zip(out["rows"], drows):
        r["theta"][field] = d["theta"][field]
    out["metadata"]["transplanted"] = {"field": field, "from_mesh": donor["metadata"].get("mesh")}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("fit")
    ap.add_argument("donor")
    ap.add_argument("out")
    ap.add_argument("--field", default="sigma_n")
    a = ap.parse_args()
    fit, donor = (json.loads(Path(p).read_text()) for p in (a.fit, a.donor))
    out = transplant(fit, donor, a.field)
    Path(a.out).write_text(json.dumps(out))
    v = lambda d: np.median([np.ravel(r["theta"][a.field])[0] for r in d["rows"]])  # noqa: E731
    print(f"{a.out}: {a.field} median {v(fit):.4f} -> {v(out):.4f} (mesh {fit['metadata'].get('mesh')})")


if __name__ == "__main__":
    main()
