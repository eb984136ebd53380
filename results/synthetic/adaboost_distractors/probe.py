"""Rendered distractors as AdaBoost negatives, screened at patch level (issue 16, stop 98).

Stop 97 (../adaboost_rounds/README.md section 6) found the synthetic cells' extra frame false positives to be soft
cloud puffs: the synthetic positives teach AdaBoost that a soft rendered blob is a drone. The remedy tried here is
the one domain-randomisation work uses (flying distractors): negatives rendered by the same pipeline (each seed's
fitted capture parameters and background, the same poses, 8-bit), with a blob (ellipsoids of several aspect ratios)
in place of the drone, so that the look of a render no longer tells the classes apart and only the shape does.

One training seed's 100-seed drone set, its negative pool and d_HOG fit (as ``../adaboost_rounds/probe_variants.py``:
AdaBoost as the library trains it, 300 rounds, 2000 candidates, the energy floor, the real-positive cascade, share
0.25, no mining). Variants: real only; + 20x synthetic as the shape cell draws it (8-bit, the seeds' fitted poses at
their offsets, shapes varied 0.3, a weak-learner critic keeping 1/4); the same + ``K``x rendered distractors per seed
as negatives; real + distractors alone; and, for comparison, the shape cell's positives without the fitted blurs or
without the object noise. Scores: patch AP of the protocol's validation and test patch sets, and ROC-AUC of the test
objects of the five small-drone videos against the ``HARD`` best background windows (IoU < 0.3 with every drone)
that seed's stored mined real-only detector keeps on every 5th frame of them (``../adaboost_rounds/puff_probe.py``'s
set; until the runner has stored that detector, this probe's own unmined real-only one picks them: ``hard_from``).
Each trained detector is kept in ``data/runs/distractor_probe/`` and read back by a later call, which then only
scores it.

    PYTHONPATH=. python results/synthetic/adaboost_distractors/probe.py SEED VARIANT [VARIANT ...]

Stop 102 added ``shape_d2`` (2x drawn) and the soft distractors ``shape_s5`` / ``shape_s2``: the library's
``distractor_negatives(style="soft")`` (the same blobs, each faint and blurred against its own background).
"""
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
import trimesh

from synthaug.data.seedset import SeedSet
from synthaug.detectors.adaboost import gradient_level, train_adaboost
from synthaug.detectors.base import load_detector, save_detector
from synthaug.detectors.training_sets import distractor_negatives, negative_pool, real_positives, synthetic_positives
from synthaug.detectors.video_training import share_weights
from synthaug.evaluate.patches import patch_eval_set, patch_metrics, score_patch_set
from synthaug.evaluate.protocol import load_protocol
from synthaug.params import CaptureParams

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "adaboost_rounds"))
from hard_windows import STEMS, hardest_windows  # noqa: E402  (../adaboost_rounds/hard_windows.py)
from stored import stored_detectors  # noqa: E402  (../adaboost_rounds/stored.py)

MESH = "../shared/data/meshes/quadcopter.glb"
HARD = 400
SHAPE_CELL = {"quantize": True, "pose_sampling": "fitted_at_seed", "shape_variation": 0.3, "realism_keep": 0.25,
              "realism_features": "weak_learners"}
# blob axes (x, y, z; normalised to a unit longest side on load): a sphere, cigars, discs, flattened cigars (the
# shapes vary through these axes; the shape cell's ``shape_variation`` would build 8 view caches a blob)
BLOBS = ((1.0, 1.0, 1.0), (1.0, 0.5, 0.5), (1.0, 0.3, 0.3), (1.0, 1.0, 0.35), (1.0, 1.0, 0.6), (1.0, 0.55, 0.3),
         (1.0, 0.75, 0.45), (1.0, 0.4, 0.2))
# name -> (synthetic positives per seed, distractor negatives per seed, fitted effects left out of the positives)
VARIANTS = {"real": (0, 0, ()), "shape": (20, 0, ()), "shape_d5": (20, 5, ()), "shape_d20": (20, 20, ()),
            "d5": (0, 5, ()), "shape_noblur": (20, 0, ("boundary_blur", "motion_blur")),
            "shape_nonoise": (20, 0, ("object_noise",)),
            # stop 102: 2x drawn; soft distractors (the library's distractor_negatives(style="soft"), faint and blurred)
            "shape_d2": (20, 2, ()), "shape_s5": (20, 5, (), "soft"), "shape_s2": (20, 2, (), "soft")}


def distractors(ss, fit, per_seed, seed, folder):
    """``per_seed * len(ss)`` blob renders, split evenly over :data:`BLOBS`, drawn as the shape cell's positives are
    (its capture parameters, poses and 8 bits; no critic, no shape variation)."""
    out = []
    for k, axes in enumerate(BLOBS):
        blob = trimesh.creation.icosphere(subdivisions=3)
        blob.apply_scale(axes)
        path = Path(folder) / f"blob{k}.ply"
        blob.export(path)
        n = per_seed * len(ss) // len(BLOBS)
        out.append(synthetic_positives(ss, str(path), fit, n, seed=seed + 100 + k,
                                       **{**SHAPE_CELL, "realism_keep": 1.0, "shape_variation": 0.0}))
    return torch.cat(out)


def hard_windows(seed, store):
    """The best background windows in the five small-drone test videos of the stored mined real-only detector (the
    runner's), or, before it exists, of this probe's own real-only detector (unmined); and which one it was."""
    ckpt, which = {cell: c for _, cell, c in stored_detectors((seed,))}.get("real"), "mined"
    if ckpt is None:
        ckpt, which = store / f"seed{seed}_real.pt", "unmined"
        if not ckpt.exists():
            return None, None
    return hardest_windows(load_detector(ckpt), HARD)[0], which


def main():
    torch.set_num_threads(1)
    seed, names = int(sys.argv[1]), sys.argv[2:]
    unknown = [n for n in names if n not in VARIANTS]
    if unknown:
        sys.exit(f"unknown variants {unknown}; known: {sorted(VARIANTS)}")
    ss = SeedSet.load(f"data/runs/ingest_drone_seed{seed}/seedsets/drone_100")
    fit = f"data/runs/fits/drone_100_seed{seed}_hog_quadcopter.json"
    effects = CaptureParams.load_with_extra(fit)[0].effects
    pos, neg = real_positives(ss), negative_pool(ss, seed=seed)
    floor = gradient_level(neg)
    proto = load_protocol("configs/protocol/halmstad_v2.json")
    kw = dict(split_file="configs/splits/halmstad.json", class_name="drone")
    sets = {s: patch_eval_set("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", s, proto, **kw)
            for s in ("val", "test")}
    small = patch_eval_set("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", "test", proto,
                           videos=list(STEMS))
    small_pos = torch.from_numpy(small.patches[small.labels == 1]).float()[:, None] / 255
    synth, dist = {}, {}
    store = Path("data/runs/distractor_probe")
    store.mkdir(parents=True, exist_ok=True)
    hard, hard_from = hard_windows(seed, store)
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            n_syn, n_dist, off, *style = VARIANTS[name]
            style = style[0] if style else "drawn"
            ckpt = store / f"seed{seed}_{name}.pt"
            t0 = time.perf_counter()
            if ckpt.exists():
                det, t_add, t_train = load_detector(ckpt), None, None
            else:
                if n_syn and (n_syn, off) not in synth:
                    kept = [e for e in effects if e not in off] if off else None
                    synth[n_syn, off] = synthetic_positives(ss, MESH, fit, n_syn * len(ss), seed=seed + 2,
                                                            effects=kept, **SHAPE_CELL)
                if n_dist and (n_dist, style) not in dist:
                    dist[n_dist, style] = (distractors(ss, fit, n_dist, seed, tmp) if style == "drawn" else
                                           distractor_negatives(ss, fit, n_dist * len(ss), seed=seed + 100,
                                                                style=style, quantize=True,
                                                                pose_sampling="fitted_at_seed"))
                added = synth[n_syn, off] if n_syn else pos[:0]
                negs = torch.cat([neg, dist[n_dist, style]]) if n_dist else neg
                t_add = round(time.perf_counter() - t0, 1)
                p = torch.cat([pos, added])
                t0 = time.perf_counter()
                det = train_adaboost(p, negs, n_rounds=300, candidates=2000, seed=seed, energy_floor=floor,
                                     positive_weights=share_weights(len(pos), len(p), 0.25),
                                     cascade_positives=len(pos) if len(added) else None)
                t_train = round(time.perf_counter() - t0, 1)
                save_detector(det, ckpt)
            row = {"seed": seed, "variant": name, "synthetic_per_seed": n_syn, "distractors_per_seed": n_dist,
                   "distractor_style": style,
                   "effects_off": list(off), "add_s": t_add, "train_s": t_train}
            for split, ps in sets.items():
                vs = score_patch_set(det, ps)
                m = patch_metrics(np.concatenate([v.scores for v in vs]), np.concatenate([v.labels for v in vs]))
                row[f"{split}_ap"] = round(m.ap.estimate, 4)
            if hard is not None:
                sp = det.score_patches(small_pos).double().numpy()
                sn = det.score_patches(hard).double().numpy()
                y = np.r_[np.ones(len(sp)), np.zeros(len(sn))].astype(int)
                row["hard_from"] = hard_from
                row["hard_auc"] = round(patch_metrics(np.r_[sp, sn], y).roc_auc.estimate, 4)
                row["hard_above_median"] = round(float((sn > np.median(sp)).mean()), 4)
            print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
