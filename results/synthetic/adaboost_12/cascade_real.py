"""Stop 59: is the + synthetic AdaBoost detectors' slowness their soft cascade, calibrated on every positive?

``train_adaboost`` sets each cascade stage's rejection threshold from the *minimum* partial score of its training
positives (minus 0.3 of the accumulated alpha). With 12 real and 240 synthetic positives, and the transfer rule
(``--ada-transfer``) letting the stumps ignore the synthetic positives least like the real ones, that minimum is set
by synthetic outliers: the thresholds of the 12-seed + synthetic detectors are 2-60x looser than the real-only
ones', so far more windows survive each stage. This script takes the stored detectors of the 12-seed + 20x
synthetic cells (``run.sh test``, stop 58), recalibrates each cascade on the 12 real positives only (same rule,
same margin), and scores both versions on the protocol's test videos side by side: AP, paired difference and
frames per second under the same load. The loose version must reproduce the stored cell's AP (a check of this
script's path). The stumps, the boxes and the mining are untouched: a proxy for training with the real-calibrated
cascade, whose mining would differ.

    PYTHONPATH=. PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 python results/synthetic/adaboost_12/cascade_real.py \
        --seeds 0 1 2 --out results/synthetic/adaboost_12/cascade_real
    # the 100-seed cells of ../adaboost_baselines/ (synthetic, perturbed, copy-paste), the stored AP as the loose one:
    ... cascade_real.py --seed-count 100 --added perturbed --stored-only --out .../cascade_real_100_perturbed
"""
from __future__ import annotations

import argparse
import copy
import json
import time
from pathlib import Path

import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.base import load_detector
from synthaug.detectors.training_sets import real_positives
from synthaug.evaluate.cells import CellCache
from synthaug.evaluate.matching import match_videos
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.runner import DataPaths, ProtocolRunner
from synthaug.evaluate.videos import detect_on_eval_set, refine_detections

WORK = Path("data/runs")


ADDED = {"synthetic": "synthetic_ratio", "perturbed": "perturb_copies", "copy-paste": "copy_paste_ratio"}


def load_docs(folder: Path) -> list[tuple[Path, dict]]:
    """Every JSON document of a cell-cache folder, read once."""
    return [(f, json.loads(f.read_text())) for f in sorted(folder.glob("*.json"))]


def stored_cells(cells: list[tuple[Path, dict]], seed: int, seed_count: int, added: str) -> tuple[Path, dict]:
    """The stored drone AdaBoost test cell of ``seed``: ``seed_count`` real seeds + 20x ``added`` positives, by
    count, transfer rule, no other option (the cells of ``run.sh`` and of ``../adaboost_baselines/``)."""
    hits = []
    for f, doc in cells:
        idn = doc.get("identity", {})
        c = idn.get("condition", {})
        others = [k for k in ADDED.values() if k != ADDED[added] and c.get(k)]
        if (c.get("kind") == "adaboost" and idn.get("class") == "drone" and c.get("seed_count") == seed_count
                and c.get(ADDED[added]) == 20 and not others and "synthetic_share" not in c
                and idn.get("seed") == seed and "eval_split" not in idn and idn.get("scales") is None
                and idn.get("options", {}).get("ada_transfer")):
            hits.append((f, doc))
    if len(hits) != 1:
        raise SystemExit(f"seed {seed}: expected one stored cell, found {[str(h[0]) for h in hits]}")
    return hits[0]


def score(det, runner: ProtocolRunner, name: str, seed: int) -> tuple[ProtocolResult, float]:
    es = runner.eval_set(1.0)
    proto = runner.protocol
    t0 = time.perf_counter()
    raw = detect_on_eval_set(det, es, scales=runner.scales, nms_iou=proto.detection.nms_iou,
                             max_detections=proto.detection.max_detections, refine_boxes=False)
    dets = refine_detections(det, es, raw, nms_iou=proto.detection.nms_iou)
    seconds = time.perf_counter() - t0
    res = ProtocolResult(name, proto, split="test", scale=1.0)
    res.add_seed(seed, videos=match_videos(es.stems, dets, es.boxes, proto), patches=(),
                 meta={"detect_s": round(seconds, 1), "fps": round(es.n_frames / seconds, 2)})
    return res, es.n_frames / seconds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--seed-count", type=int, default=12)
    ap.add_argument("--added", choices=list(ADDED), default="synthetic")
    ap.add_argument("--stored-only", action="store_true",
                    help="take the every-positive cascade's AP from the stored cell instead of scoring it again")
    ap.add_argument("--protocol", default="configs/protocol/halmstad_v2.json")
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args()
    torch.set_num_threads(1)
    proto = load_protocol(a.protocol)
    paths = DataPaths(work_dir=str(WORK))  # the runner's default folders and split, as run.sh used them
    runner = ProtocolRunner(proto, "drone", paths, CellCache(WORK / "cells", read_only=True),
                            scale_check=False, patches=False)
    cells, detectors = load_docs(WORK / "cells"), load_docs(WORK / "cells" / "detectors")
    loose_parts, tight_parts, rows = [], [], []
    for seed in a.seeds:
        cell_path, cell = stored_cells(cells, seed, a.seed_count, a.added)
        stored = ProtocolResult.from_json(cell["result"]["scales"]["1.0"])
        # the cell's detector: the detector store's entry with the cell's training metadata
        det_doc = next(doc for _, doc in detectors if doc.get("result", {}).get("meta") == cell["result"]["train"])
        det_file = WORK / "cells" / "detectors" / det_doc["result"]["file"]
        loose = load_detector(det_file)
        pos = real_positives(SeedSet.load(cell["result"]["train"]["positives"]["seedset"]))
        tight = copy.deepcopy(loose)
        tight.calibrate_cascade(pos, quantile=0.0, margin=0.3)  # train_adaboost's rule, on the real positives only
        name = f"{a.seed_count} real + 20x {a.added}"
        if a.stored_only:
            r_loose, fps_loose = stored, None
            r_loose.condition = f"{name} (cascade from every positive)"
        else:
            r_loose, fps_loose = score(loose, runner, f"{name} (cascade from every positive)", seed)
        r_tight, fps_tight = score(tight, runner, f"{name} (cascade from the real positives)", seed)
        row = {"seed": seed, "cell": cell_path.name, "detector": det_file.name, "stored_ap": stored.mean_ap(),
               "loose_ap": r_loose.mean_ap(), "tight_ap": r_tight.mean_ap(),
               "fps_loose": None if fps_loose is None else round(fps_loose, 2), "fps_tight": round(fps_tight, 2),
               "fps_stored": stored.seeds[seed].meta.get("fps"),  # the cell's own run, under its load then
               "rejection_loose": [round(float(v), 3) for v in loose.rejection[:5]],
               "rejection_tight": [round(float(v), 3) for v in tight.rejection[:5]]}
        print(json.dumps(row), flush=True)
        rows.append(row)
        loose_parts.append(r_loose)
        tight_parts.append(r_tight)
    a.out.mkdir(parents=True, exist_ok=True)
    ProtocolResult.combine(loose_parts, condition=loose_parts[0].condition).save(a.out / "cascade_all_positives.json")
    ProtocolResult.combine(tight_parts, condition=tight_parts[0].condition).save(a.out / "cascade_real_positives.json")
    (a.out / "per_seed.json").write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
