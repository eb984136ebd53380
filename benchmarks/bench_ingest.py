"""Benchmark: ingest every shared halmstad video (drone + airplane, and birds as hard negatives).

    python benchmarks/bench_ingest.py [--data ../shared/data/halmstad] [--workers 2] [--out DIR]

Prints one JSON object: wall-clock seconds of the whole run (fresh output
folder, so nothing is skipped), videos processed, the median seconds per video
inside a worker, background methods and the seed sets written.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", default=str(REPO.parent / "shared/data/halmstad"))
    p.add_argument("--split", default=str(REPO / "configs/splits/halmstad.json"))
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", help="output folder (default: a temporary one, deleted)")
    p.add_argument("--splits", nargs="+", default=["train", "val", "test"])
    args = p.parse_args()

    from synthaug.data.ingest import IngestConfig, ingest_videos

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.out) if args.out else Path(tmp) / "ingest"
        t0 = time.perf_counter()
        report = ingest_videos(Path(args.data) / "videos", Path(args.data) / "labels", out, split=args.split,
                               splits=args.splits, cfg=IngestConfig(), seed_counts=(12, 25, 50, 100),
                               workers=args.workers, progress=False, redo=True)
        wall = time.perf_counter() - t0
    per_video = [v["seconds"] for v in report["videos"].values()]
    classes: dict[str, int] = {}
    for v in report["videos"].values():
        classes[v["class"]] = classes.get(v["class"], 0) + 1
    print(json.dumps({
        "benchmark": "ingest_halmstad", "workers": args.workers, "splits": args.splits,
        "wall_seconds": round(wall, 1), "videos": len(per_video), "videos_per_class": classes,
        "failed": report["failed"], "median_seconds_per_video_in_worker": round(statistics.median(per_video), 3),
        "background_methods": report["background_methods"], "box_cleanup": report["box_cleanup"],
        "seed_sets": [f"{s['class']}_{s['requested']}: {s['seeds']} seeds / {s['videos']} videos"
                      for s in report["seed_sets"]],
    }, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
