"""Per-seed fitting Θ^(i) = argmin_Θ d(X_i, S(Θ, B_i)) over a whole seed set: every name in one place.

Each concept has its own module; this one re-exports their names, so ``from synthaug.fit.fitting import
FitConfig, fit_seedset`` (and every other name it held) keeps working:

1. ``config`` — :class:`FitConfig` (a fit's options), :func:`build_distance`, :func:`seed_seed`,
   :func:`patches_tensor`;
2. ``starts`` — :func:`pose_grid_starts` / :func:`neutral_u`: the structured start of a seed's search;
3. ``search`` — one seed's fit: :func:`fit_objective`, :func:`search`, :func:`fit_one`;
4. ``fingerprint`` — what a fit depends on (:func:`fit_inputs`, :func:`what_changed`, the digests) and which
   finished parts of an earlier run may be reused;
5. ``worker`` — what one process does: fit a group of seeds in lockstep, one part per seed;
6. ``run`` — :func:`fit_seedset`: a whole seed set, resumable, in-process, on local processes or on Dask,
   assembled into one capture-parameter file.
"""

from __future__ import annotations

# the private names too: scripts and tests imported them from here before the split
from synthaug.fit.config import (
    INITS,
    OBJECT_NOISE,
    FitConfig,
    _cfg_json,
    _warm_cache,
    build_distance,
    patches_tensor,
    seed_seed,
)
from synthaug.fit.fingerprint import (
    _INPUT_NAMES,
    _check_parts,
    _hash_object,
    _read_part,
    fit_inputs,
    log,
    mesh_digest,
    object_digest,
    seedset_digest,
    what_changed,
)
from synthaug.fit.run import (
    RESULT_FORMAT,
    RESULT_VERSION,
    _assemble,
    _dask_client,
    _fit_parts,
    _probe_dask,
    _run_dask,
    fit_seedset,
)
from synthaug.fit.search import fit_objective, fit_one, search
from synthaug.fit.starts import neutral_u, pose_grid_starts
from synthaug.fit.worker import _CTX, _context, _fit_indices, _groups

__all__ = [
    "INITS",
    "OBJECT_NOISE",
    "RESULT_FORMAT",
    "RESULT_VERSION",
    "FitConfig",
    "build_distance",
    "patches_tensor",
    "seed_seed",
    "neutral_u",
    "pose_grid_starts",
    "fit_objective",
    "fit_one",
    "search",
    "fit_inputs",
    "mesh_digest",
    "object_digest",
    "seedset_digest",
    "what_changed",
    "fit_seedset",
]

