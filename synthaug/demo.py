"""``synthaug demo``: the whole method on data the project makes itself, in a few minutes.

1. **Measured data.** Short panning videos (procedural panoramas) with a
   quadcopter flying in them, rendered through the view cache with the paper's
   object-stage effects (material, motion blur) at per-video random capture
   parameters; per-frame boxes in the shared label format. Videos are split by
   video into train and test.
2. **Ingest** the train videos (aligned-median backgrounds) into a seed set.
3. **Fit** Θ per seed in HOG space (``synthaug fit``'s machinery).
4. **Generate** synthetic patches from the fit (random poses, seeds' capture
   parameters) and **train** the HOG detector on real seeds only and on real +
   synthetic.
5. **Evaluate** AP on the test videos, and write ``README.md`` (table),
   ``preview.png`` (real | background | synthetic), ``fitted_pairs.png`` (Fig. 8),
   ``joint_histograms.png`` (Fig. 4) and ``pr_*.png``.
6. **Diagnose** (issue 6): measured data from the reference camera with one
   camera effect hidden (``--hidden``, default rotor_blur), a normal fit, and
   ``synthaug diagnose`` naming what the simulation misses (``diagnosis/``);
   the same without the effect as the control (``diagnosis_clean/``).

Everything is seeded; a rerun reproduces the numbers.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import add_option, int_at_least, positive_float, positive_int

    # numbers are checked as they are parsed (a bad one exits 2 at once, naming the option)
    parser.add_argument("--out", default="outputs/demo", help="output folder")
    parser.add_argument("--videos", type=int_at_least(2), default=20,
                        help="generated videos (40%% test; of the rest, 15%% of all validation when >= 6, the "
                             "others train; >= 2)")
    parser.add_argument("--frames", type=int_at_least(10), default=90, help="frames per video (>= 10)")
    add_option(parser, "--seed-counts", aliases=["--seeds"], type=positive_int, default=25,
               help="seed images drawn from the train videos")
    parser.add_argument("--budget", type=int_at_least(10), default=800, help="fit evaluations per seed (>= 10)")
    parser.add_argument("--ratio", type=positive_float, default=20, help="synthetic patches per real seed (> 0)")
    parser.add_argument("--object-box", choices=["seed", "none"], default="seed",
                        help="synthetic objects framed as ingest frames a labelled seed (seed) or at the mesh's scale "
                             "(none, the paper's)")
    parser.add_argument("--detector", default="hog", choices=["hog", "adaboost", "cnn"],
                        help="detector trained on real seeds only and on real + synthetic")
    add_option(parser, "--frame-stride", aliases=["--stride"], type=positive_int, default=3,
               help="score every k-th test frame")
    parser.add_argument("--seed", type=int, default=0, help="seeds everything: videos, fits, training")
    parser.add_argument("--training-seeds", type=positive_int, default=3,
                        help="detectors trained per condition (seeds --seed, --seed + 1, ...): the comparison is "
                             "paired over them")
    parser.add_argument("--fit-init", default="grid", choices=["grid", "uniform"], help="how each fit starts")
    parser.add_argument("--hidden", default="rotor_blur",
                        help="camera effect hidden in the diagnosis step's measured data (issue 6); 'none' skips "
                             "the step")
    parser.add_argument("--diagnosis-seeds", type=int_at_least(4), default=60,
                        help="seeds of the diagnosis step (>= 4: two folds of two)")


class RenderedQuadcopter:
    """``object_fn`` for :func:`synthaug.data.synthvideo.make_panning_video`: the mesh through the view cache.

    One video = one set of capture parameters (material, motion blur) and a
    slowly turning pose; the object is ``size_px`` pixels (mesh unit length).
    """

    def __init__(self, cache: Any, *, size_px: float, seed: int) -> None:
        from synthaug.params import CaptureParams

        g = torch.Generator().manual_seed(seed)
        self.cache = cache
        self.size_px = size_px
        self.theta = CaptureParams.sample(1, generator=g, ranges={"w_d": (0.05, 0.35), "sigma_u": (0.3, 1.5),
                                                                 "sigma_v": (0.0, 0.6)})
        self.pose0 = torch.rand(3, generator=g, dtype=torch.float64) * torch.tensor([2 * math.pi, 0.8, 2 * math.pi])
        self.pose0[1] += 0.4  # seen from below/side, as a drone in the sky

    def __call__(self, index: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        from synthaug.effects import functional as Fx

        side = int(math.ceil(self.size_px / 0.5 / 2)) * 2
        a = self.pose0[0] + 0.02 * index
        b = self.pose0[1] + 0.15 * math.sin(0.05 * index)
        g = self.pose0[2] + 0.01 * index
        t = torch.tensor
        cov, nrm = self.cache.layers(t([a]), t([b]), t([g]), t([0.0]), t([0.0]), size=side,
                                     object_scale=self.size_px / side)
        color = Fx.diffuse_material(nrm, cov, self.theta.w_d)
        color, cov = Fx.motion_blur(color, cov, self.theta.sigma_u, self.theta.sigma_v, self.theta.alpha_m, pad=15)
        return (color[0, 0].numpy() * 255.0).astype(np.float32), cov[0, 0].numpy().astype(np.float32)


def make_measured_videos(out: Path, *, n_videos: int, n_frames: int, seed: int, cache: Any) -> dict[str, list[str]]:
    """Generated train/test videos in the shared format; returns the split."""
    from synthaug.data.splits import VideoSplit, save_split
    from synthaug.data.synthvideo import make_panning_video

    stems = []
    rng = np.random.default_rng(seed)
    for k in range(n_videos):
        name = f"V_DEMO_{k:03d}"
        fn = RenderedQuadcopter(cache, size_px=float(rng.uniform(14, 30)), seed=seed * 1000 + k)
        make_panning_video(out, n_frames=n_frames, size=(320, 256), object_fn=fn, seed=seed * 1000 + k, name=name,
                           texture="textured" if k % 2 else "flat")
        stems.append(name)
    n_test = max(1, int(round(0.4 * n_videos)))
    n_val = int(round(0.15 * n_videos)) if n_videos >= 6 else 0  # mining stops on them (none for tiny runs)
    train = stems[:-n_test]
    split = {"train": train[:len(train) - n_val], "val": train[len(train) - n_val:], "test": stems[-n_test:]}
    save_split(VideoSplit(videos=split, classes={s: "drone" for s in stems}, info={"dataset": "synthaug demo"}),
               out / "split.json")
    return split


def validate(args: argparse.Namespace) -> None:
    """Everything checked before the first video is made: ``--hidden`` names a known effect, ``--out`` can be a
    folder (numbers are checked by argparse). Raises ValueError naming the option."""
    from synthaug._checks import check_output_dir
    from synthaug.diagnose.reference_camera import resolve_hidden

    check_output_dir(args.out)
    if args.hidden != "none":
        try:
            resolve_hidden([args.hidden])
        except ValueError as e:
            raise ValueError(f"--hidden: {e} (or 'none')") from None


def main(args: argparse.Namespace) -> int:
    import shutil
    import sys

    try:
        validate(args)
    except ValueError as e:
        print(f"synthaug demo: error: {e}", file=sys.stderr)
        return 2
    out = Path(args.out)
    fresh = not out.exists()
    try:
        return _run(args)
    except BaseException:
        if fresh:  # a failed or interrupted demo leaves no half-written folder behind (it is not resumable)
            shutil.rmtree(out, ignore_errors=True)
        raise


def _run(args: argparse.Namespace) -> int:
    from synthaug.data.ingest import ingest_videos
    from synthaug.data.seedset import SeedSet
    from synthaug.evaluate.videos import load_eval_set
    from synthaug.fit.fitting import FitConfig, fit_seedset
    from synthaug.fit.plots import plot_fitted_pairs, plot_joint_histograms
    from synthaug.render.cache import ViewCache

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    cache = ViewCache.build("quadcopter")
    data = out / "measured"
    split = make_measured_videos(data, n_videos=args.videos, n_frames=args.frames, seed=args.seed, cache=cache)
    timings["make data"] = time.perf_counter() - t0

    t = time.perf_counter()
    ingest_videos(data / "videos", data / "labels", out / "ingest", split=data / "split.json",
                  seed_counts=(args.seed_counts, 2 * args.seed_counts), progress=False, workers=2)
    seed_dir = out / "ingest" / "seedsets" / f"drone_{args.seed_counts}"
    seeds = SeedSet.load(seed_dir)
    timings["ingest"] = time.perf_counter() - t

    t = time.perf_counter()
    fit_path = out / "fit_hog.json"
    fit_seedset(seed_dir, "quadcopter", fit_path, FitConfig(distance="hog", budget=args.budget, seed=args.seed, init=args.fit_init),
                workers=2)
    timings["fit"] = time.perf_counter() - t

    t = time.perf_counter()
    eval_set = load_eval_set(split["test"], data / "videos", data / "labels", stride_k=args.frame_stride)
    names = ("real seeds only", f"real + {args.ratio:g}x synthetic (ours)", "2x real seeds (reference)")
    seed_dir2 = out / "ingest" / "seedsets" / f"drone_{2 * args.seed_counts}"
    results, first = _train_and_score(args, data, split, (seed_dir, seed_dir, seed_dir2), fit_path, eval_set, names)
    for (name, slug) in zip(names, ("real", "ours")):
        _plot_pr(first[name], out / f"pr_{slug}.png", title=f"{args.detector}: {name} (training seed 0)")
    timings["train + evaluate"] = time.perf_counter() - t

    from synthaug.data.preview import main as preview_main

    preview_main(argparse.Namespace(out=str(out / "preview.png"), mesh="quadcopter", seed_set=str(seed_dir),
                                    params=str(fit_path), n=8, per_seed=4, mode="patch", patch_size=40, zoom=3,
                                    effects=None, seed=args.seed, step_deg=5.0))
    plot_fitted_pairs(seeds, {"hog": fit_path}, out / "fitted_pairs.png", n=8)
    plot_joint_histograms(fit_path, out / "joint_histograms.png")
    diagnosis = None
    if args.hidden != "none":
        t = time.perf_counter()
        diagnosis = (diagnose_hidden(out / "diagnosis", hidden=args.hidden, n_seeds=args.diagnosis_seeds,
                                     budget=args.budget, seed=args.seed),
                     diagnose_hidden(out / "diagnosis_clean", hidden=None, n_seeds=args.diagnosis_seeds,
                                     budget=args.budget, seed=args.seed))
        timings["diagnosis"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t0
    counts = {names[0]: len(seeds), names[1]: len(seeds) + int(round(args.ratio * len(seeds))),
              names[2]: len(SeedSet.load(seed_dir2))}
    table, verdict, summaries = _comparison(results, names)
    _write_report(out, args, counts, table, verdict, timings, len(seeds), split, diagnosis)
    summary = {"out": str(out), **{n: round(summaries[n].ap[0.5].estimate, 4) for n in names},
               "difference": summaries[names[1]].paired.difference.to_json() if summaries[names[1]].paired else None,
               "difference_seeds_resampled": (summaries[names[1]].paired_seeds.difference.to_json()
                                              if summaries[names[1]].paired_seeds else None),
               "reference_difference": (summaries[names[2]].paired.difference.to_json()
                                        if summaries[names[2]].paired else None),
               "verdict": verdict}
    if diagnosis is not None:
        summary["diagnosis"] = {"hidden": args.hidden, "findings": [f["effect"] for f in diagnosis[0]["findings"]],
                                "clean_findings": [f["effect"] for f in diagnosis[1]["findings"]]}
    print(json.dumps({**summary, "seconds": round(timings["total"], 1)}))
    return 0


def diagnose_hidden(out: Path, *, hidden: str | None, n_seeds: int, budget: int, seed: int) -> dict[str, Any]:
    """The diagnosis at work: measured data with ``hidden`` switched on, a normal fit, ``synthaug diagnose``.

    The measured seed set comes from the reference camera
    (:func:`~synthaug.diagnose.reference_camera.make_measured_seedset`: whole
    frames through a richer camera, cut into seed patches like ingested ones);
    the fit is ``synthaug fit``'s (CMA-ES from a random start, HOG distance,
    no knowledge of the truth); the report lands in ``out/report.md``.
    """
    from synthaug.diagnose.reference_camera import make_measured_seedset
    from synthaug.diagnose.report import diagnose
    from synthaug.fit.fitting import FitConfig, fit_seedset

    seeds = make_measured_seedset(out / "seeds", n_seeds=n_seeds, hidden=[hidden] if hidden else None,
                                  frame_size=(192, 256),
                                  object_px=(20.0, 32.0), view_step_deg=10, sprite_size=64, seed=seed + 7,
                                  paper_ranges={"w_d": (0.3, 0.45)})
    cfg = FitConfig(distance="hog", budget=budget, seed=seed, step_deg=10, sprite_size=64)
    fit_seedset(seeds, "quadcopter", out / "fit_hog.json", cfg, workers=2)
    return diagnose(seeds, "quadcopter", out / "fit_hog.json", out_dir=out, k=5 if n_seeds >= 10 else 2)


def demo_protocol(frame_stride: int, training_seeds: int) -> Any:
    """The evaluation protocol of the demo's generated test videos: ``halmstad_v1``'s rules (AP at IoU 0.5 and
    0.3, video bootstrap, paired differences) on the demo's split, every ``frame_stride``-th frame."""
    from synthaug.evaluate.protocol import Protocol, example_protocol_dict

    stride = {"frame_stride": int(frame_stride)}
    return Protocol.from_dict(example_protocol_dict(
        name="synthaug_demo", split_file=None, description="synthaug demo: its generated test videos",
        test={"split": "test", **stride}, val={"split": "val", **stride}, min_training_seeds=int(training_seeds),
        scale_check=[]))


def _train_and_score(args: argparse.Namespace, data: Path, split: dict[str, list[str]], seed_dirs: tuple[Path, ...],
                     fit_path: Path, eval_set: Any, names: tuple[str, ...]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Each condition (real seeds, + synthetic, twice the real seeds: ``seed_dirs``) trained with each training seed
    by ``synthaug train``'s function (:func:`~synthaug.detectors.video_training.train_from_videos`: the seed set's
    negatives, box regression from the training videos' labels, hard-negative mining over the training videos
    stopped on the validation videos)
    and matched on the test videos: ``{name: ProtocolResult}`` and training seed 0's pooled PR curve per name."""
    from synthaug.detectors.training import TrainOptions
    from synthaug.detectors.video_training import AddedPositives, train_from_videos
    from synthaug.evaluate.ap import evaluate_detections
    from synthaug.evaluate.matching import match_videos
    from synthaug.evaluate.results import ProtocolResult
    from synthaug.evaluate.videos import detect_on_eval_set

    proto = demo_protocol(args.frame_stride, args.training_seeds)
    results = {n: ProtocolResult(n, proto) for n in names}
    first: dict[str, Any] = {}
    # the ridge map (the ensemble's CNN map costs minutes); without validation videos the mining's stopping rule has
    # nothing to count, so one mining round instead of the default's
    options = TrainOptions(box_model="ridge", mining_rounds=TrainOptions.mining_rounds if split["val"] else 1)
    object_box = None if args.object_box == "none" else args.object_box
    conditions = (AddedPositives(), AddedPositives(params=fit_path, synthetic_ratio=args.ratio, object_box=object_box),
                  AddedPositives())
    for seed in range(args.training_seeds):
        s = args.seed + seed
        for name, seed_dir, added in zip(names, seed_dirs, conditions):
            det, _ = train_from_videos(args.detector, "drone", data / "videos", data / "labels",
                                       split=data / "split.json", seed=s, seedset=seed_dir, added=added,
                                       options=options, negative_classes=(), extra_negatives=1000)
            dets = detect_on_eval_set(det, eval_set, nms_iou=proto.detection.nms_iou,
                                      max_detections=proto.detection.max_detections)
            results[name].add_seed(seed, videos=match_videos(eval_set.stems, dets, eval_set.boxes, proto))
            if seed == 0:
                first[name] = evaluate_detections([d for v in dets for d in v], [b for v in eval_set.boxes for b in v],
                                                  proto.main_iou)
    return results, first


def _comparison(results: dict[str, Any], names: tuple[str, ...]) -> tuple[str, str, dict[str, Any]]:
    """The protocol's table (AP with video-bootstrap CIs, the paired differences) and plain sentences on it: what
    synthetic data did, and, beside it, what twice the real seeds did (whether this detector gains from more
    positives on these videos at all)."""
    from synthaug.evaluate.summary import report_table, summarize_conditions

    summaries = summarize_conditions(results, baseline=names[0])
    table = report_table(results, baseline=names[0])
    paired = summaries[names[1]].paired
    n = len(summaries[names[1]].seeds)
    if paired is None:
        return table, f"No paired comparison ({summaries[names[1]].paired_note}).", summaries
    d = paired.difference
    ci = f"{d.estimate:+.3f} [{d.low:+.3f}, {d.high:+.3f}]"
    unit = f"paired over {n} training seeds, 95 % interval from resampling the {summaries[names[0]].n_videos} test videos"
    if d.low > 0:
        verdict = f"Synthetic data raised AP@0.5 by {ci} ({unit}): the gain the method exists for."
    elif d.high < 0:
        verdict = (f"Synthetic data LOWERED AP@0.5 by {ci} ({unit}): this run does not show the gain the "
                   "method exists for.")
    else:
        verdict = (f"No significant change in AP@0.5: {ci} ({unit}); the interval includes 0, so this run does "
                   "not show a gain from synthetic data.")
    crossed = summaries[names[1]].paired_seeds
    if crossed is not None and n > 1:
        c = crossed.difference
        verdict += (f" Counting training randomness as well (the training seeds resampled with the videos): "
                    f"[{c.low:+.3f}, {c.high:+.3f}]{'' if n >= 5 else f', coarse with {n} seeds'}.")
    ref = summaries[names[2]].paired if len(names) > 2 else None
    if ref is not None:
        r = ref.difference
        rci = f"{r.estimate:+.3f} [{r.low:+.3f}, {r.high:+.3f}]"
        if r.low > 0:
            verdict += f" Twice the real seeds raised it by {rci}: this detector does gain from more positives here."
        else:
            verdict += (f" Twice the real seeds changed it by {rci}: on these videos this detector does not gain from "
                        "more real positives either, so added positives of any kind have little to give.")
    return table, verdict, summaries


def _plot_pr(res: Any, path: Path, *, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4, 3.4))
    if len(res.recall):
        ax.plot(np.asarray(res.recall), np.asarray(res.precision))
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("recall")
    ax.set_ylabel("precision")
    ax.set_title(f"{title}\nAP = {res.ap:.3f}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _write_report(out: Path, args: argparse.Namespace, counts: dict[str, int], table: str, verdict: str,
                  timings: dict[str, float], n_seeds: int, split: dict[str, list[str]],
                  diagnosis: tuple[dict[str, Any], dict[str, Any]] | None = None) -> None:
    lines = [
        "# synthaug demo",
        "",
        f"Generated measured data: {args.videos} panning videos x {args.frames} frames (320x256), quadcopter "
        f"rendered with per-video capture parameters; train videos {split['train']}, validation videos "
        f"{split['val']}, test videos {split['test']}.",
        f"Seeds: {n_seeds} from the train videos; Θ fitted per seed in HOG space ({args.budget} evaluations).",
        f"Detector: {args.detector}, trained by `synthaug train`'s function (box regression from the training "
        f"videos' labels, hard-negative mining over them, stopped on the validation videos; one round when there are none) with "
        f"{args.training_seeds} training seeds per condition; synthetic objects framed "
        + ("as ingest frames a labelled seed (`object_box='seed'`)" if args.object_box == "seed" else
           "at the mesh's scale (the paper's)") + f"; AP on one test frame in {args.frame_stride}.",
        "",
        "| training positives | count |",
        "|---|---|",
        *(f"| {name} | {n} |" for name, n in counts.items()),
        "",
        f"**{verdict}**",
        "",
        table,
    ]
    lines += ["", "Figures: `preview.png` (real | background | synthetic from the fit), `fitted_pairs.png`,",
              "`joint_histograms.png`, `pr_real.png`, `pr_ours.png`.", "",
              ]
    if diagnosis is not None:
        found = [f["effect"] for f in diagnosis[0]["findings"]]
        clean = [f["effect"] for f in diagnosis[1]["findings"]]
        lines += ["## Diagnosis (what the simulation misses)", "",
                  f"Measured data from the reference camera with **{args.hidden}** hidden "
                  f"({diagnosis[0]['inputs']['n_seeds']} seeds), fitted by `synthaug fit` (no knowledge of the "
                  "truth), then `synthaug diagnose`: ranked findings "
                  + (", ".join(f"**{e}**" for e in found) if found else "**none significant**")
                  + (" — the hidden effect is named first." if found[:1] == [args.hidden] else
                     " — the hidden effect is NOT named first.")
                  + " Full report: `diagnosis/report.md`.",
                  "The same camera without the hidden effect (`diagnosis_clean/report.md`): "
                  + (", ".join(f"**{e}**" for e in clean) if clean else "nothing significant") + ".", ""]
    lines += ["Timings (s): " + ", ".join(f"{k} {v:.0f}" for k, v in timings.items()), "",
              f"Command: `synthaug demo --out {args.out}`", ""]
    (out / "README.md").write_text("\n".join(lines))
