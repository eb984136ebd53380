"""Issue 16, item 1 on the real drone seeds: how far the training positives of each condition are from the
real seed patches in the detectors' features (HOG; the CNN's own d_CNN network), per training seed.

    OMP_NUM_THREADS=1 PYTHONPATH=. python results/synthetic/drone_v1/measure_gap.py   # from the repository root
    # the object-noise fix: d_HOG fits with σ_n measured vs fitted, in HOG features only
    # AdaBoost's own features (weak-learner responses of each training seed's real-only detector, one per --seeds):
    #   ... --families hog adaboost --adaboost-detectors D0.pt D1.pt D2.pt --fits hog --no-perturbed --fitted-renders
    OMP_NUM_THREADS=1 PYTHONPATH=. python results/synthetic/drone_v1/measure_gap.py --fits hog hog_measured \
        --families hog --no-perturbed --pose-sampling uniform fitted --fitted-renders --out results/synthetic/drone_v1/gap_factors

Reads the seed sets the runner's cells drew (data/runs/ingest_drone_seed{s}/seedsets/drone_100) and the fits
(data/runs/fits/drone_100_seed{s}_{hog,cnn}.json); writes gap_seed{s}.json + figures under
results/synthetic/drone_v1/gap/ and prints one line per (seed, comparison, family).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from synthaug.data.items import BACKGROUND_SAMPLING
from synthaug.data.poses import POSE_SAMPLING, FittedPose, SeedOffset
from synthaug.data.seedset import SeedSet
from synthaug.detectors.critic import realism_variants
from synthaug.diagnose.gap import gap_section, training_samples
from synthaug.distances.cnn import cnn_distance
from synthaug.effects.camera_functional import quantize_levels
from synthaug.effects.perturb import perturb_patches
from synthaug.params import CaptureParams

MESH = "../shared/data/meshes/quadcopter.glb"
OUT = Path("results/synthetic/drone_v1/gap")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fits", nargs="+", default=["hog", "cnn"], help="fit files data/runs/fits/drone_100_seed{s}_<name>.json")
    ap.add_argument("--families", nargs="+", default=["hog", "cnn"], choices=["hog", "cnn", "adaboost"])
    ap.add_argument("--adaboost-detectors", nargs="+", default=None,
                    help="with --families adaboost: a trained AdaBoost detector (save_detector file) per --seeds "
                         "entry, in the same order; its weak learners give the features")
    ap.add_argument("--no-perturbed", action="store_true", help="leave out the perturbed real patches")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--pose-sampling", nargs="+", default=["uniform"], choices=list(POSE_SAMPLING),
                    help="poses of the synthetic samples (each fit once per choice)")
    ap.add_argument("--pose-jitter", nargs="+", type=float, default=[20.0],
                    help="with --pose-sampling fitted*: the spread of the rotation around each fitted pose, degrees "
                         "(FittedPose's jitter_deg), one comparison each; 20: the library's default")
    ap.add_argument("--object-box", nargs="+", default=["none"], choices=["none", "seed", "fit"],
                    help="framing of the synthetic objects (SyntheticObjectDataset's object_box), one comparison each")
    ap.add_argument("--shape-variation", type=float, nargs="+", default=[0.0],
                    help="the synthetic objects' shape variation (SyntheticObjectDataset's shape_variation), one "
                         "comparison each; 0: the mesh alone")
    ap.add_argument("--effects-off", nargs="+", default=["none"],
                    help="synthetic samples once per value: none (every fitted effect) or effects joined by + left out, "
                         "e.g. boundary_blur+motion_blur (the CNN's default)")
    ap.add_argument("--quantize", nargs="+", choices=["off", "on"], default=["off"],
                    help="synthetic samples once per value: on rounds them to 8-bit levels as the real frames are "
                         "(synthaug train --quantize)")
    ap.add_argument("--background-sampling", nargs="+", choices=list(BACKGROUND_SAMPLING), default=["seed"],
                    help="synthetic samples once per value: other puts each object on another seed's background "
                         "(synthaug train --background-sampling); the held-out groups stay the capture seeds")
    ap.add_argument("--realism-keep", nargs="+", type=float, default=[1.0],
                    help="synthetic samples once per value: under 1, drawn 1/K times over and the K least synthetic to "
                         "the cross-fitted HOG critic kept (synthaug train --realism-keep)")
    ap.add_argument("--realism-selection", nargs="+", choices=["seed", "set"], default=["seed"],
                    help="with --realism-keep under 1, once per value: seed (each seed's share of its own draws, "
                         "training's default since stop 83) or set (the least synthetic of the whole draw, stop 82's; "
                         "synthaug train --realism-selection)")
    ap.add_argument("--fitted-renders", action="store_true",
                    help="also each fit's own renders S(Θ_i, B_i) (the fitted pose itself: no pose sampling)")
    ap.add_argument("--seed-set", default="data/runs/ingest_drone_seed{s}/seedsets/drone_100",
                    help="seed set of training seed {s}")
    ap.add_argument("--fit", default="data/runs/fits/drone_100_seed{s}_{dist}.json",
                    help="fit file of training seed {s} and fit name {dist}")
    ap.add_argument("--mesh", default=MESH, help="mesh file or built-in name")
    ap.add_argument("--out", default=str(OUT))
    args = ap.parse_args()
    out = Path(args.out)
    if "adaboost" in args.families and (args.adaboost_detectors is None
                                        or len(args.adaboost_detectors) != len(args.seeds)):
        ap.error("--families adaboost needs --adaboost-detectors, one per --seeds entry")
    torch.set_num_threads(1)
    out.mkdir(parents=True, exist_ok=True)
    for i_seed, s in enumerate(args.seeds):
        t0 = time.perf_counter()
        ss = SeedSet.load(args.seed_set.format(s=s))
        n = len(ss)
        real = torch.as_tensor(np.asarray(ss.patches)).float().div(255).unsqueeze(1)
        groups = np.arange(n)
        syn = {}
        for dist in args.fits:
            fit = Path(args.fit.format(s=s, dist=dist))
            if fit.is_file():
                fit_effects = CaptureParams.load_with_extra(fit)[0].effects
                unknown = sorted({e for off in args.effects_off if off != "none" for e in off.split("+")}
                                 - set(fit_effects))
                if unknown:
                    ap.error(f"--effects-off: {unknown} not among the effects of {fit} ({list(fit_effects)})")
                poses = [(ps, j) for ps in args.pose_sampling
                         for j in (args.pose_jitter if ps.startswith("fitted") else [20.0])]
                for ps, jit in poses:
                    sampler: object = ps
                    if jit != 20.0:  # FittedPose's default spread is what the name stands for
                        sampler = FittedPose(fit, jit)
                        sampler = SeedOffset(sampler, fit) if ps.endswith("_at_seed") else sampler
                    for box in args.object_box:
                        for sv in args.shape_variation:
                            for off, qz, bs, (rk, sel) in ((o, q, b, k) for o in args.effects_off
                                                           for q in args.quantize for b in args.background_sampling
                                                           for k in realism_variants(args.realism_keep,
                                                                                     args.realism_selection)):
                                gone = [] if off == "none" else off.split("+")
                                name = (f"synthetic_{dist}" + ("" if ps == "uniform" else f"_{ps}_poses")
                                        + ("" if jit == 20.0 else f"_jitter_{jit:g}")
                                        + ("" if box == "none" else f"_box_{box}")
                                        + ("" if not sv else "_shapes_" + f"{sv:g}".replace(".", "p"))
                                        + ("" if not gone else "_without_" + "_".join(gone))
                                        + ("_8bit" if qz == "on" else "")
                                        + ("" if bs == "seed" else "_other_backgrounds")
                                        + ("" if rk == 1 else "_critic_" + f"{rk:g}".replace(".", "p"))
                                        + ("_per_seed" if sel == "seed" else ""))
                                effects = None if not gone else [e for e in fit_effects if e not in gone]
                                syn[name] = training_samples(ss, args.mesh, fit, 5 * n, seed=s + 2,
                                                             pose_sampling=sampler,  # type: ignore[arg-type]
                                                             object_box=None if box == "none" else box,
                                                             shape_variation=sv, effects=effects,
                                                             quantize=qz == "on", background_sampling=bs,
                                                             realism_keep=rk, realism_selection=sel)
                if args.fitted_renders:
                    from synthaug.fit.render_fit import render_fitted

                    fitted = render_fitted(ss, fit, args.mesh)[1].clamp(0, 1)
                    syn[f"fitted_renders_{dist}"] = (fitted, groups)
                    if "on" in args.quantize:
                        syn[f"fitted_renders_{dist}_8bit"] = (quantize_levels(fitted), groups)
        if not args.no_perturbed:
            per = perturb_patches(real, 5, generator=torch.Generator().manual_seed(s + 3))
            syn["perturbed"] = (per, np.tile(groups, 5))
        detectors = {}
        if "adaboost" in args.families:
            detectors["adaboost"] = args.adaboost_detectors[i_seed]
        if "cnn" in args.families:  # the CNN family in the features of a network trained on this seed set's real patches
            neg = torch.as_tensor(np.asarray(ss.negatives)).float().div(255).unsqueeze(1)
            detectors["cnn"] = cnn_distance(positives=real, negatives=neg, seed=s).net
        res = gap_section(real, syn, real_groups=groups, families=tuple(args.families), detectors=detectors,
                          seed=s, out_dir=out / f"seed{s}", permutations=100, kid_subsets=50)
        (out / f"gap_seed{s}.json").write_text(json.dumps(res, indent=1) + "\n")
        for name, comp in res["comparisons"].items():
            for fam, r in comp["families"].items():
                t = r["two_sample"]
                print(f"seed {s} {name:14s} {fam}: accuracy {t['accuracy']:.3f} [{t['ci'][0]:.3f}, {t['ci'][1]:.3f}] "
                      f"p_perm {t.get('p_permutation')}, KID {r['kid']['mean']:.4f}", flush=True)
        print(f"seed {s}: {time.perf_counter() - t0:.0f} s", flush=True)


if __name__ == "__main__":
    main()
