"""The drone 100-seed seed sets and d_HOG fits that ``measure.py`` reads, made as the runner makes them.

For each training seed s: the seed set ``synthaug train`` / the runner ingest for ``--seed-counts 100`` (the
protocol's split file, ingest seed s, bird videos as hard negatives) into ``<work>/ingest_drone_seed{s}``, and its fit
``<work>/fits/drone_100_seed{s}_hog_quadcopter.json`` (``FitConfig(distance="hog")``, the runner's
``--fit-distance hog`` with ``quadcopter.glb``). Existing seed sets and fits are reused.

    OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl PYTHONPATH=. python results/synthetic/recipe_gap/prepare.py --seeds 3 4 5
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch

from synthaug.detectors.video_training import _seed_set_by_ingest, discover_videos, split_by_video
from synthaug.fit.fitting import FitConfig, fit_seedset


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", required=True)
    ap.add_argument("--work", default="data/runs")
    ap.add_argument("--videos", default="../shared/data/halmstad/videos")
    ap.add_argument("--labels", default="../shared/data/halmstad/labels")
    ap.add_argument("--split", default="configs/splits/halmstad.json")
    ap.add_argument("--mesh", default="../shared/data/meshes/quadcopter.glb")
    args = ap.parse_args()
    torch.set_num_threads(1)
    vs = discover_videos(args.videos, args.labels)
    work = Path(args.work)
    for s in args.seeds:
        sp = split_by_video(vs, "drone", split=args.split, seed=s, negative_classes=("bird",))
        t0 = time.perf_counter()
        seedset = work / f"ingest_drone_seed{s}"
        _seed_set_by_ingest(vs, sp, 100, seedset, ingest_seed=s, workers=1, log=print, negative_classes=("bird",))
        fit = work / "fits" / f"drone_100_seed{s}_hog_quadcopter.json"
        t1 = time.perf_counter()
        if not fit.is_file():
            fit.parent.mkdir(parents=True, exist_ok=True)
            fit_seedset(seedset / "seedsets" / "drone_100", args.mesh, fit, FitConfig(distance="hog"))
        print(f"seed {s}: ingest {t1 - t0:.0f} s, fit {time.perf_counter() - t1:.0f} s", flush=True)


if __name__ == "__main__":
    main()
