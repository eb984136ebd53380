"""``synthaug ingest``: videos + boxes (or images + COCO) -> seed sets with backgrounds.

Examples::

    # the shared halmstad videos, train split, drone and airplane seed sets of 12/25/50/100
    synthaug ingest --videos ../shared/data/halmstad/videos --labels ../shared/data/halmstad/labels \\
        --split configs/splits/halmstad.json --out data/halmstad --seed-counts 12 25 50 100

    # an image folder with COCO boxes
    synthaug ingest --images my/images --coco my/annotations.json --out data/mine --seed-counts 12 25

Safe to interrupt and rerun: finished videos are kept and not redone, unless their video file, label file,
split or the options changed since (then they are redone, and the warning says why). Workers die with the
command, even after a ``kill -9``.
"""

from __future__ import annotations

import argparse
import json
import sys

__all__ = ["add_arguments", "main"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import add_option, dataclass_defaults, float_in, int_at_least, nonneg_int, positive_int
    from synthaug.data.ingest import IngestConfig

    d = dataclass_defaults(IngestConfig)  # the options' defaults are IngestConfig's
    # numbers are checked as they are parsed: a bad one exits 2 at once, naming the option
    src = parser.add_argument_group("input (videos + labels, or images + COCO)")
    src.add_argument("--videos", help="folder of videos (V_*.mp4), matched to label files by stem")
    src.add_argument("--labels", help="folder of per-video label JSON files (halmstad format)")
    src.add_argument("--images", help="folder of images (with --coco)")
    src.add_argument("--coco", help="COCO JSON file with bbox annotations (with --images)")
    parser.add_argument("--out", required=True, help="output folder: pool/, seedsets/<class>_<n>/, ingest_report.json")
    parser.add_argument("--split", help="split JSON (videos: configs/splits/halmstad.json format; COCO: "
                                        "{train: [...], val: [...], test: [...]} of file names). "
                                        "Default: everything is train")
    parser.add_argument("--splits", nargs="+", default=["train"], choices=["train", "val", "test"],
                        help="splits to ingest into the pool (seed sets are drawn from train only)")
    add_option(parser, "--seed-counts", aliases=["--seeds"], type=positive_int, nargs="*", default=[12, 25, 50, 100],
               help="seed-set sizes to draw per class")
    parser.add_argument("--classes", nargs="+", help="known classes; a label file of another class is an error")
    parser.add_argument("--hard-negative-classes", nargs="*", default=list(d["hard_negative_classes"]),
                        help="classes whose videos give hard negatives only")
    parser.add_argument("--patch-size", type=int_at_least(8), default=d["patch_size"],
                        help="seed patch side P (40 as the paper)")
    parser.add_argument("--object-fraction", type=float_in(0, 1, low_open=True), default=d["object_fraction"],
                        help="the box's longest side spans this fraction of the patch")
    parser.add_argument("--per-video", type=positive_int, default=d["seeds_per_video"],
                        help="seed candidates per video")
    parser.add_argument("--negatives-per-video", type=nonneg_int, default=d["negatives_per_video"],
                        help="random object-free background crops kept per train video")
    parser.add_argument("--hard-negatives-per-video", type=nonneg_int, default=d["hard_negatives_per_video"],
                        help="object-free crops near the object (clutter next to it) kept per train video")
    parser.add_argument("--inpaint", default=d["inpaint_method"], choices=["pushpull", "telea", "ns"],
                        help="fill used where aligned frames cannot serve")
    parser.add_argument("--seed", type=int, default=d["seed"], help="base random seed")
    parser.add_argument("--workers", type=positive_int, default=2, help="parallel worker processes")
    parser.add_argument("--limit", type=positive_int, help="ingest at most this many videos (quick look)")
    parser.add_argument("--redo", action="store_true", help="reprocess videos even if their shard is current")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def main(args: argparse.Namespace) -> int:
    from synthaug.data.ingest import IngestConfig, ingest_coco, ingest_videos
    from synthaug.data.video import IngestInputError

    video_mode = bool(args.videos or args.labels)
    coco_mode = bool(args.images or args.coco)
    if video_mode == coco_mode or (video_mode and not (args.videos and args.labels)) or \
            (coco_mode and not (args.images and args.coco)):
        print("synthaug ingest: give either --videos and --labels, or --images and --coco", file=sys.stderr)
        return 2
    if any(n < 1 for n in args.seed_counts):
        print(f"synthaug ingest: --seed-counts must be >= 1, got {args.seed_counts}", file=sys.stderr)
        return 2
    try:
        cfg = IngestConfig(patch_size=args.patch_size, object_fraction=args.object_fraction,
                           seeds_per_video=args.per_video, negatives_per_video=args.negatives_per_video,
                           hard_negatives_per_video=args.hard_negatives_per_video, seed=args.seed,
                           classes=tuple(args.classes) if args.classes else None,
                           hard_negative_classes=tuple(args.hard_negative_classes), inpaint_method=args.inpaint)
        common = dict(cfg=cfg, seed_counts=args.seed_counts, workers=args.workers, progress=not args.no_progress,
                      redo=args.redo)
        if video_mode:
            report = ingest_videos(args.videos, args.labels, args.out, split=args.split, splits=args.splits,
                                   limit=args.limit, **common)
        else:
            report = ingest_coco(args.coco, args.images, args.out, split=args.split, **common)
    except (IngestInputError, ValueError, FileNotFoundError) as e:
        print(f"synthaug ingest: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("synthaug ingest: interrupted; finished videos are kept, rerun the same command to continue",
              file=sys.stderr)
        return 130
    short = {k: report[k] for k in ("processed", "skipped_current", "background_methods", "box_cleanup",
                                    "seconds_total")}
    short["failed"] = report["failed"]
    short["seed_sets"] = [f"{s['path']} ({s['seeds']} seeds from {s['videos']} videos)" for s in report["seed_sets"]]
    if report.get("redone"):  # shards made from other inputs (an edited label file...), made again
        short["redone"] = report["redone"]
    if report.get("stale_seed_sets"):  # seed sets of an earlier run with other inputs, not redrawn
        short["stale_seed_sets"] = report["stale_seed_sets"]
    print(json.dumps(short, indent=1))
    for stem, msg in report["failed"].items():
        print(f"synthaug ingest: {stem} failed: {msg}", file=sys.stderr)
    return 1 if report["failed"] else 0
