"""Train HOG 100 seeds (seed 0) exactly as the runner does, save it, dump raw detections at x1 and x2."""
# scratch folder: data/analysis/x2 (detectors and raw detections; not committed). Run from the repository root.
import pickle, sys, time
from pathlib import Path
import torch
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.runner import ProtocolRunner, DataPaths, Condition
from synthaug.detectors.video_training import train_from_videos, AddedPositives
from synthaug.detectors.base import save_detector, load_detector
from synthaug.evaluate.videos import detect_on_eval_set

if __name__ == "__main__":
    torch.set_num_threads(1)
    kind = sys.argv[1] if len(sys.argv) > 1 else "hog"
    split = sys.argv[2] if len(sys.argv) > 2 else "test"
    out = Path("data/analysis/x2")
    proto = load_protocol()
    r = ProtocolRunner(proto, "drone", DataPaths(), eval_split=split)
    ck = out / f"{kind}100_s0.pt"
    if not ck.exists():
        t0 = time.time()
        det, meta = train_from_videos(kind, "drone", r.paths.videos_dir, r.paths.labels_dir, split=r.paths.split_file,
                                      seed=0, seed_count=100, added=AddedPositives(), options=r.options,
                                      work_dir=Path(r.paths.work_dir) / "ingest_drone_seed0", ingest_seed=0, log=print)
        save_detector(det, ck)
        print("trained", time.time() - t0)
    det = load_detector(ck)
    for s in (1.0, 2.0):
        es = r.eval_set(s)
        t0 = time.time()
        raw = detect_on_eval_set(det, es, nms_iou=proto.detection.nms_iou, max_detections=proto.detection.max_detections,
                                 refine_boxes=False)
        print("x", s, time.time() - t0)
        pickle.dump({"raw": raw, "boxes": es.boxes, "stems": es.stems}, open(out / f"{kind}_raw_{split}_x{s:g}.pkl", "wb"))
