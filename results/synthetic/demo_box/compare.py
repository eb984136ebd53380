"""Issue 16 on `synthaug demo`'s generated videos: real seeds only vs real + synthetic, trained by `synthaug train`'s
function, 3 training seeds, paired, video-bootstrap 95 % intervals (the demo's protocol).

The videos come from a finished `synthaug demo --out DIR --videos 20 --seed S --hidden none` run (DIR/measured). The
demo's train videos are split again here (the last three become validation videos, on which mining stops); the seed
set is ingested by `train_from_videos` into DIR/compare_work_<seeds>, and fitted once (`synthaug fit`'s HOG fit,
budget 800) into DIR/compare_fit_<seeds>_<object_noise>.json.

    PYTHONPATH=. python results/synthetic/demo_box/compare.py DIR [--seeds 25] [--ratio 20] [--object-box seed]
        [--pose uniform|fitted] [--share S] [--object-noise fit|measured] [--oracle S] [--pixel-wd]

--oracle S replaces the fitted capture parameters by the truth of demo seed S's videos (oracle.py); --pixel-wd
re-solves each seed's w_d by pixel least squares after the fit (resolve.py). Prints one line per condition.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


def main() -> None:
    from synthaug.data.splits import VideoSplit, save_split
    from synthaug.demo import demo_protocol
    from synthaug.detectors.training import TrainOptions
    from synthaug.detectors.video_training import AddedPositives, train_from_videos
    from synthaug.evaluate.matching import match_videos
    from synthaug.evaluate.results import ProtocolResult
    from synthaug.evaluate.summary import summarize_conditions
    from synthaug.evaluate.videos import detect_on_eval_set, load_eval_set
    from synthaug.fit.fitting import FitConfig, fit_seedset

    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--seeds", type=int, default=25)
    ap.add_argument("--ratio", type=float, default=20)
    ap.add_argument("--training-seeds", type=int, default=3)
    ap.add_argument("--detector", default="hog")
    ap.add_argument("--n-val", type=int, default=3)
    ap.add_argument("--object-noise", default="fit")
    ap.add_argument("--pose", default="uniform")
    ap.add_argument("--object-box", default=None)
    ap.add_argument("--share", type=float, default=None)
    ap.add_argument("--oracle", type=int, default=None)
    ap.add_argument("--pixel-wd", action="store_true")
    ap.add_argument("--tag", default="")
    a = ap.parse_args()
    out = Path(a.out)
    sp = json.loads((out / "measured/split.json").read_text())
    train, test = sp["train"] + sp["val"], sp["test"]
    split = {"train": train[:-a.n_val], "val": train[-a.n_val:], "test": test}
    sfile = out / "compare_split.json"
    save_split(VideoSplit(videos=split, classes={s: "drone" for s in train + test}, info={"dataset": "demo + val"}),
               sfile)
    videos, labels = out / "measured/videos", out / "measured/labels"
    eval_set = load_eval_set(test, videos, labels, stride_k=3)
    proto = demo_protocol(3, a.training_seeds)
    fit_path = out / f"compare_fit_{a.seeds}_{a.object_noise}.json"

    def params(seed_dir: Path) -> Path:
        if not fit_path.exists():
            fit_seedset(seed_dir, "quadcopter", fit_path,
                        FitConfig(distance="hog", budget=800, seed=0, init="grid", object_noise=a.object_noise), workers=1)
        path = fit_path
        if a.pixel_wd:
            from resolve import resolve_wd
            from synthaug.data.seedset import SeedSet

            path = fit_path.with_name(fit_path.stem + "_pixel_wd.json")
            if not path.exists():
                resolve_wd(SeedSet.load(seed_dir), fit_path, path)
        if a.oracle is not None:
            from oracle import write_oracle

            path = write_oracle(path, seed_dir, a.oracle, fit_path.with_name(fit_path.stem + "_oracle.json"))
        return path

    names = ["real", "ours"]
    results = {n: ProtocolResult(n, proto) for n in names}
    options = TrainOptions(box_model="ridge")
    t0 = time.perf_counter()
    for s in range(a.training_seeds):
        for n in names:
            added = AddedPositives() if n == "real" else AddedPositives(
                params=params, synthetic_ratio=a.ratio, pose_sampling=a.pose, synthetic_share=a.share,
                object_box=a.object_box)
            det, _ = train_from_videos(a.detector, "drone", videos, labels, split=sfile, seed=s, seed_count=a.seeds,
                                       work_dir=out / f"compare_work_{a.seeds}", added=added, options=options,
                                       negative_classes=(), ingest_workers=1)
            dets = detect_on_eval_set(det, eval_set, nms_iou=proto.detection.nms_iou,
                                      max_detections=proto.detection.max_detections)
            results[n].add_seed(s, videos=match_videos(eval_set.stems, dets, eval_set.boxes, proto))
    summ = summarize_conditions(results, baseline="real")
    for n in names:
        sm = summ[n]
        d = sm.paired.difference if sm.paired else None
        print(f"{a.out} {a.tag} {n:5s} AP@0.5 {sm.ap[0.5].estimate:.3f} AP@0.3 {sm.ap[0.3].estimate:.3f}"
              + ("" if d is None else f"  diff {d.estimate:+.3f} [{d.low:+.3f}, {d.high:+.3f}]")
              + f"  ({time.perf_counter() - t0:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
