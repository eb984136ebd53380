"""Pose initialisation of the fit: ``init="uniform"`` (CMA-ES's uniform look) vs ``init="grid"`` (rotation grid).

On a reference-camera seed set (known truth; no hidden effects) each seed is
fitted with ``FitConfig(distance=..., budget=B, step_deg=10, sprite_size=64,
init=...)`` for every init and budget, in-process on one torch thread, the
way ``synthaug fit`` does it. Reported per (init, budget): the median fitted
distance, the median rotation error (geodesic angle between the fitted and
the true R, the minimum over the quadcopter's four rotations about its up
axis), the share of seeds within 20° / 45°, and the median seconds per seed.
Reference: the distance at the true Θ, and a fit started at the truth
(a local CMA-ES, steps 0.05 of each range, budget ``--truth-budget``; cf.
``tests/test_diagnose.py::converged_fit``).
With ``--real`` (default data/halmstad/seedsets/drone_25, skipped when
absent) the same inits are compared on real seeds by median fitted distance
(no truth there).

Usage (prints one JSON document)::

    python benchmarks/bench_fit_init.py --n-seeds 24 --budgets 800 3500 --n-real 12
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch


def symmetric_rotation_error(fit: np.ndarray, truth: np.ndarray, order: int = 4) -> np.ndarray:
    """Degrees between R(fit) and R(truth) (rows of (α, β, γ)), minimised over ``order`` turns about z (object up)."""
    from synthaug.fit.objective import rotation_angle
    from synthaug.render.pose import rotation_matrices, rotation_matrix

    rf = rotation_matrices(fit[:, 0], fit[:, 1], fit[:, 2])
    rt = rotation_matrices(truth[:, 0], truth[:, 1], truth[:, 2])
    sym = [rotation_matrix(0.0, 0.0, 2 * math.pi * k / order) for k in range(order)]
    # the object frame's symmetry acts on the right: R and R·Rz(k·90°) show the same object
    return np.degrees(np.min([rotation_angle(rf, rt @ s) for s in sym], axis=0))


def _summary(rows: list[dict]) -> dict:
    d = np.array([r["distance"] for r in rows])
    out = {"n": len(rows), "distance_median": round(float(np.median(d)), 4),
           "distance_mean": round(float(np.mean(d)), 4),
           "seconds_per_seed_median": round(float(np.median([r["seconds"] for r in rows])), 3)}
    if "n_evals" in rows[0]:
        out["n_evals_median"] = int(np.median([r["n_evals"] for r in rows]))
    if "rot_err_deg" in rows[0]:
        e = np.array([r["rot_err_deg"] for r in rows])
        out.update(rot_err_deg_median=round(float(np.median(e)), 2), within_20deg=round(float(np.mean(e < 20)), 3),
                   within_45deg=round(float(np.mean(e < 45)), 3))
    return out


def run(seeds_dir: Path, mesh: str, inits: list[str], budgets: list[int], distance: str, *, truth: bool,
        truth_budget: int, n: int | None, seed: int) -> dict:
    from synthaug.data.seedset import SeedSet
    from synthaug.fit.fitting import FitConfig, build_distance, fit_one, patches_tensor, seed_seed
    from synthaug.fit.objective import FitSpace, RenderObjective
    from synthaug.fit.optimizers import get_optimizer
    from synthaug.params import CaptureParams
    from synthaug.render.cache import ViewCache

    seeds = SeedSet.load(seeds_dir)
    idx = list(range(len(seeds) if n is None else min(n, len(seeds))))
    cache = ViewCache.build(mesh, step_deg=10, sprite_size=64)
    dist = build_distance(distance, seeds, seed=seed)
    scale = float(seeds.object_fraction)
    rows_truth = None
    if truth:
        from synthaug.diagnose.reference_camera import load_truth

        t, textra, _ = load_truth(seeds_dir)
        td = t.as_dict()
        tvec = CaptureParams({k: td[k] for k in CaptureParams.vector_names()}, validate=False)
        true_pose = np.stack([t.alpha.double().numpy(), t.beta.double().numpy(), t.gamma.double().numpy()], 1)
    out: dict = {"seeds": str(seeds_dir), "mesh": str(mesh), "n_seeds": len(idx), "distance": distance, "runs": {}}
    for budget in budgets:
        for init in inits:
            cfg = FitConfig(distance=distance, budget=budget, step_deg=10, sprite_size=64, init=init, seed=seed)
            rows = []
            for i in idx:
                s = seed_seed(cfg.seed, i)
                t0 = time.perf_counter()
                res = fit_one(patches_tensor(seeds.patches[i:i + 1]), patches_tensor(seeds.backgrounds[i:i + 1]),
                              cache, dist, cfg, seed=s, object_scale=scale)
                row = {"distance": res["distance"], "seconds": time.perf_counter() - t0, "n_evals": res["stats"]["n_evals"]}
                if truth:
                    th = res["theta"]
                    row["rot_err_deg"] = float(symmetric_rotation_error(np.array([th[:3]]), true_pose[i:i + 1])[0])
                rows.append(row)
            out["runs"][f"{init}@{budget}"] = _summary(rows)
            print(f"{init}@{budget}: {out['runs'][f'{init}@{budget}']}", file=sys.stderr, flush=True)
    if truth:
        # the same search space as the fits above; the truth's scale as the start's scale
        cfg = FitConfig(distance=distance, budget=truth_budget, step_deg=10, sprite_size=64, seed=seed)
        at, conv = [], []
        for i in idx:
            s = seed_seed(cfg.seed, i)
            space = FitSpace.default(bounds=dict(cfg.bounds), scale_range=(cfg.scale_range[0] * scale,
                                                                           cfg.scale_range[1] * scale))
            x0 = space.from_theta(tvec[i])[0]
            x0[-1] = space.scale_to_u(float(textra[i]["object_scale"]))
            tgt, bg = patches_tensor(seeds.patches[i:i + 1]), patches_tensor(seeds.backgrounds[i:i + 1])
            at.append(float(RenderObjective(tgt, bg, cache, dist, space, object_scale=scale, noise_seed=s)(x0)[0]))
            # a local search from the truth: CMA-ES with small steps (0.05 of each range) started there
            obj = RenderObjective(tgt, bg, cache, dist, space, object_scale=scale, noise_seed=s)
            res = get_optimizer("cmaes").minimize(obj, space.dim, seed=s, budget=truth_budget, starts=x0[None],
                                                  stds=np.full(space.dim, 0.05))
            fitted = space.to_theta(res.x[None]).wrapped().to_vector()[0].numpy()
            conv.append({"distance": min(res.fun, at[-1]), "seconds": 0.0,
                         "rot_err_deg": float(symmetric_rotation_error(fitted[None, :3], true_pose[i:i + 1])[0])})
        out["truth"] = {"distance_at_truth_median": round(float(np.median(at)), 4),
                        f"fit_from_truth@{truth_budget}": {k: v for k, v in _summary(conv).items()
                                                           if not k.startswith("seconds")}}
        print(f"truth: {out['truth']}", file=sys.stderr, flush=True)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-seeds", type=int, default=24, help="reference-camera seeds")
    parser.add_argument("--budgets", type=int, nargs="+", default=[800, 3500])
    parser.add_argument("--inits", nargs="+", default=["uniform", "grid"])
    parser.add_argument("--distance", default="hog")
    parser.add_argument("--seed", type=int, default=0, help="fit seed")
    parser.add_argument("--data-seed", type=int, default=7, help="reference-camera seed")
    parser.add_argument("--truth-budget", type=int, default=800)
    parser.add_argument("--real", default="data/halmstad/seedsets/drone_25")
    parser.add_argument("--real-mesh", default="../shared/data/meshes/quadcopter.glb")
    parser.add_argument("--n-real", type=int, default=12, help="real seeds (0: skip)")
    args = parser.parse_args()
    torch.set_num_threads(1)
    from synthaug.diagnose.reference_camera import make_measured_seedset

    result: dict = {"command": " ".join(["python"] + sys.argv), "torch_threads": 1}
    with tempfile.TemporaryDirectory() as tmp:
        sd = make_measured_seedset(Path(tmp) / "ref", n_seeds=args.n_seeds, hidden=None, frame_size=(192, 256),
                                   object_px=(20.0, 32.0), view_step_deg=10, sprite_size=64, seed=args.data_seed,
                                   paper_ranges={"w_d": (0.3, 0.45)})
        result["reference_camera"] = run(sd, "quadcopter", args.inits, args.budgets, args.distance, truth=True,
                                         truth_budget=args.truth_budget, n=None, seed=args.seed)
    real, mesh = Path(args.real), Path(args.real_mesh)
    if args.n_real > 0 and real.is_dir() and mesh.is_file():
        result["real"] = run(real, str(mesh), args.inits, args.budgets, args.distance, truth=False,
                             truth_budget=0, n=args.n_real, seed=args.seed)
    elif args.n_real > 0:
        result["real"] = f"skipped: {real} or {mesh} not found"
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
