"""Per-seed fitting Θ^(i) = argmin_Θ d(X_i, S(Θ, B_i)) over a whole seed set.

:func:`fit_seedset` writes a capture-parameter file (``CaptureParams.save``
format, so :class:`~synthaug.data.synthetic.SyntheticObjectDataset` reads it
directly) with, per seed, the fitted Θ and in ``extra`` the final distance,
the optimiser's statistics and trace, and the seed's provenance.

It is resumable: each finished seed is written atomically to a ``.parts``
folder beside the output (:mod:`synthaug.fit.worker`); a rerun skips finished seeds whose inputs are
unchanged (:mod:`synthaug.fit.fingerprint`), and since every seed
has its own generator seed (a hash of the base seed and the seed index) the
final file is identical whether the run was interrupted or not, and whatever
the number of processes. Runs in-process, on local processes
(``workers > 1``), or on a Dask cluster (``dask_address``).
Local workers die with their parent (:mod:`synthaug._procs`), so a ``kill -9``
leaves no process behind.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import torch

from synthaug._io import digest, exclusive_lock
from synthaug.fit.config import FitConfig, _cfg_json, _warm_cache, build_distance
from synthaug.fit.fingerprint import _check_parts, fit_inputs
from synthaug.fit.worker import _context, _fit_indices, _groups
from synthaug.params import FIT_RESULT_FORMAT as RESULT_FORMAT
from synthaug.params import FIT_RESULT_VERSION as RESULT_VERSION
from synthaug.params import CaptureParams, atomic_write_text


def fit_seedset(
    seeds_path: str | os.PathLike,
    mesh: Any,
    out_path: str | os.PathLike,
    cfg: FitConfig = FitConfig(),
    *,
    workers: int = 1,
    dask_address: str | None = None,
    indices: Sequence[int] | None = None,
    progress: bool | Callable[[int, int], None] = False,
    distance: Any = None,
    lockstep: int = 8,
) -> Path:
    """Fit every seed of a seed set and write the capture-parameter file.

    Args:
        seeds_path: seed-set folder (``synthaug ingest`` output).
        mesh: mesh path or built-in name.
        out_path: output JSON (capture-parameter format, plus per-seed extras).
        cfg: fit options.
        workers: local processes (1 = in this process).
        dask_address: a Dask scheduler address (``tcp://...``), or a
            ``distributed.Client`` / ``LocalCluster`` object; overrides ``workers``.
        indices: fit only these seeds (default: all).
        progress: show a tqdm bar (True) or call ``progress(done, total)``.
        distance: a prebuilt distance (default: :func:`build_distance` on the seeds).
        lockstep: seeds fitted together in one process, their optimisers' populations scored in one batch
            (:mod:`synthaug.fit.lockstep`; the fits are the same as one at a time, only faster: issue 19).

    Returns:
        the output path.
    """
    from synthaug.data.seedset import SeedSet

    if not isinstance(lockstep, int) or isinstance(lockstep, bool) or lockstep < 1:
        raise ValueError(f"lockstep must be an int >= 1, got {lockstep!r}")
    seeds_path = str(Path(seeds_path))
    seeds = SeedSet.load(seeds_path)  # validates the seed set (clear errors) before any work
    n = len(seeds)
    if n == 0:
        raise ValueError(f"seed set {seeds_path} holds no seeds")
    todo_all = list(range(n)) if indices is None else sorted({int(i) for i in indices})
    bad = [i for i in todo_all if not 0 <= i < n]
    if bad:
        raise ValueError(f"seed indices out of range for {n} seeds: {bad[:5]}")
    from synthaug.render.mesh import load_mesh

    load_mesh(mesh)  # a missing/corrupt mesh fails here, naming the file
    if seeds.patches.shape[-1] < 16:
        raise ValueError(f"seed patches of {seeds.patches.shape[-1]} px are too small to fit")
    out = Path(out_path)
    if out.is_dir():
        raise ValueError(f"the output {out} is a directory; give the path of a JSON file (--out)")
    if isinstance(dask_address, str):
        _probe_dask(dask_address)  # a dead or malformed scheduler address fails before the distance is built
    # a caller-given distance is hashed as given (a built one follows from cfg and the seed set)
    inputs = fit_inputs(seeds_path, mesh, cfg, distance)
    if distance is None:
        distance = build_distance(cfg.distance, seeds, seed=cfg.seed, **cfg.distance_kwargs)
    fingerprint = {"digest": digest(inputs), "inputs": inputs}
    cache = _warm_cache(mesh, cfg)  # checks step_deg / sprite_size; sprites built once before workers load them
    client = _dask_client(dask_address) if isinstance(dask_address, str) else dask_address  # a dead one fails now
    parts = out.parent / f".{out.name}.parts"
    # two runs into one output take turns (the second would otherwise assemble from parts the first has removed)
    with exclusive_lock(out.parent / f".{out.name}.lock"):
        fresh = not parts.exists()
        try:
            parts.mkdir(parents=True, exist_ok=True)
            _fit_parts(seeds, seeds_path, mesh, cfg, distance, parts, out, fingerprint, todo_all, cache,
                       workers=workers, dask_address=client, progress=progress, lockstep=lockstep)
        except BaseException:
            if fresh and not any(parts.glob("seed_*.json")):  # nothing to resume: leave nothing behind
                shutil.rmtree(parts, ignore_errors=True)
            raise
        finally:
            if client is not None and client is not dask_address:
                client.close()
        if indices is None:
            shutil.rmtree(parts, ignore_errors=True)
    return out


def _fit_parts(seeds: Any, seeds_path: str, mesh: Any, cfg: FitConfig, distance: Any, parts: Path, out: Path,
         fingerprint: dict[str, Any], todo_all: list[int], cache: Any, *, workers: int,
         dask_address: Any, progress: bool | Callable[[int, int], None], lockstep: int = 1) -> None:
    """Fit the seeds not finished yet (of ``todo_all``) into ``parts``, ``lockstep`` at a time, then assemble ``out``."""
    done = _check_parts(parts, fingerprint)
    todo = [i for i in todo_all if i not in done]
    bar = None
    if progress is True:
        from tqdm import tqdm

        bar = tqdm(total=len(todo_all), initial=len(todo_all) - len(todo), unit="seed", desc=f"fit {cfg.distance}")

    def tick() -> None:
        if bar is not None:
            bar.update(1)
        elif callable(progress):
            progress(len({int(p.stem.split("_")[1]) for p in parts.glob("seed_*.json")}), len(todo_all))

    if dask_address is not None:
        _run_dask(dask_address, todo, seeds_path, mesh, cfg, distance, str(parts), tick, fingerprint,
                  lockstep=lockstep)
    elif workers <= 1:
        # one thread, as in worker processes (same floating-point results); the caller's setting is restored
        threads = torch.get_num_threads()
        try:
            _context(seeds_path, mesh, cfg, distance, seeds=seeds, cache=cache)
            for group in _groups(todo, lockstep):
                for _ in _fit_indices(group, seeds_path, mesh, cfg, distance, str(parts), fingerprint):
                    tick()
        finally:
            torch.set_num_threads(threads)
    else:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor, as_completed

        from synthaug._procs import pool_kwargs

        # workers die with this process (a kill -9 of the command leaves nothing running)
        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"), **pool_kwargs()) as ex:
            futs = [ex.submit(_fit_indices, group, seeds_path, mesh, cfg, distance, str(parts), fingerprint)
                    for group in _groups(todo, min(lockstep, -(-len(todo) // workers)))]
            for f in as_completed(futs):
                for _ in f.result():
                    tick()
    if bar is not None:
        bar.close()
    _assemble(seeds, todo_all, cfg, mesh, seeds_path, parts, out, fingerprint["digest"])


def _probe_dask(address: str, *, timeout_s: float = 10.0) -> None:
    """Fail at once, naming ``--dask``, when ``address`` cannot be a live scheduler: ``distributed`` is missing,
    or a ``tcp://host:port`` address is malformed or refuses a plain socket (known in milliseconds, where a
    ``distributed.Client`` would retry for 30 s)."""
    import importlib.util
    import socket
    from urllib.parse import urlsplit

    if importlib.util.find_spec("distributed") is None:
        raise ValueError("--dask needs the 'distributed' package (pip install distributed)")
    parsed = urlsplit(address if "://" in address else f"tcp://{address}")
    if parsed.scheme != "tcp":
        return
    try:
        host, port = parsed.hostname, parsed.port
    except ValueError:
        host, port = None, None
    if not host or port is None:
        raise ValueError(f"--dask: {address!r} is not a scheduler address (tcp://HOST:PORT)")
    try:
        socket.create_connection((host, port), timeout=timeout_s).close()
    except OSError as e:
        raise ValueError(f"--dask: no Dask scheduler answers at {address} ({e.strerror or e})") from None


def _dask_client(address: str, *, timeout_s: float = 10.0) -> Any:
    """A ``distributed.Client`` on ``address`` (probed first by :func:`_probe_dask`), connected within
    ``timeout_s``; errors name ``--dask``."""
    _probe_dask(address, timeout_s=timeout_s)
    from distributed import Client

    try:
        return Client(address, timeout=f"{timeout_s}s")
    except (OSError, TimeoutError, ValueError) as e:
        raise ValueError(f"--dask: cannot connect to the Dask scheduler at {address} ({e})") from None


def _run_dask(address: Any, todo: list[int], seeds_path: str, mesh: Any, cfg: FitConfig, distance: Any,
              parts: str, tick: Callable[[], None], fingerprint: dict[str, Any] | None = None, *,
              lockstep: int = 1) -> None:
    from distributed import Client, as_completed

    own = isinstance(address, str)
    client = Client(address) if own else (address if isinstance(address, Client) else Client(address))
    try:
        dist_f = client.scatter(distance, broadcast=True)
        futs = [client.submit(_fit_indices, group, seeds_path, mesh, cfg, dist_f, parts, fingerprint, pure=False)
                for group in _groups(todo, lockstep)]
        for f in as_completed(futs):
            for _ in f.result():
                tick()
    finally:
        if own or not isinstance(address, Client):
            client.close()


def _assemble(seeds: Any, indices: list[int], cfg: FitConfig, mesh: Any, seeds_path: str, parts: Path,
              out: Path, fingerprint: str | None = None) -> None:
    rows, extra, timing = [], [], []
    for i in indices:
        res = json.loads((parts / f"seed_{i:05d}.json").read_text())
        if fingerprint is not None and res.get("fingerprint") != fingerprint:  # another run wrote it meanwhile
            raise RuntimeError(f"{parts / f'seed_{i:05d}.json'} was written by a run with other inputs "
                               f"while this one ran (two runs into the same --out?); rerun the command")
        rows.append(res["theta"])
        rec = seeds.records[i] if i < len(seeds.records) else {}
        stats = dict(res["stats"])
        # wall-clock figures go to a side file: the fit file itself is reproducible byte for byte
        timing.append({"seed_index": i, "seconds": stats.pop("seconds", None), "wall_s": stats.pop("wall_s", None),
                       "init_wall_s": stats.pop("init_wall_s", None)})
        extra.append({"seed_index": i, "distance": res["distance"], "generator_seed": res["generator_seed"],
                      "object_scale": res["object_scale"],
                      "optimizer": stats, "video": rec.get("video"), "frame": rec.get("frame"),
                      "class": rec.get("class")})
    channels = 1
    theta = CaptureParams.from_vector(torch.tensor(rows, dtype=torch.float64), channels=channels,
                                      effects=cfg.effects)
    meta = {"result_format": RESULT_FORMAT, "result_version": RESULT_VERSION, "config": _cfg_json(cfg),
            "seeds": seeds_path, "mesh": str(mesh),
            **({"inputs_fingerprint": fingerprint} if fingerprint is not None else {}),
            "object_scale": cfg.object_scale if cfg.object_scale is not None else float(seeds.object_fraction),
            "distance_median": float(np.median([e["distance"] for e in extra]))}
    theta.save(out, extra=extra, metadata=meta)
    secs = [t["seconds"] for t in timing if t["seconds"] is not None]
    atomic_write_text(out.with_name(out.stem + ".timing.json"), json.dumps(
        {"median_seconds_per_seed": float(np.median(secs)) if secs else None, "per_seed": timing}, indent=1))
