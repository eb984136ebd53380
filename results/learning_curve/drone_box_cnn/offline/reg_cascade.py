"""Cascades of box regressors (stage k applied to stage k-1's boxes), scored on dumped raw detections."""
import pickle, sys, time, copy, json
import numpy as np, torch
from synthaug.detectors.base import load_detector
from synthaug.detectors.boxes import BoxRegressor
from synthaug.detectors.frames import VideoFrames
from synthaug.detectors.video_training import discover_videos, split_by_video
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.runner import ProtocolRunner, DataPaths
from synthaug.evaluate.videos import refine_detections
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.matching import match_videos

if __name__ == "__main__":
    torch.set_num_threads(1)
    kind, split = sys.argv[1], sys.argv[2]
    cascades = eval(sys.argv[3])
    det = load_detector(f"data/analysis/x2/{kind}100_s0.pt")
    proto = load_protocol(); r = ProtocolRunner(proto, "drone", DataPaths(), eval_split=split)
    vs = discover_videos(r.paths.videos_dir, r.paths.labels_dir)
    sp = split_by_video(vs, "drone", split=r.paths.split_file, seed=0)
    src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["train"], stride=15)
    bw = det.box_in_window; aspect = bw[2] / bw[3]
    dumps = {s: pickle.load(open(f"data/analysis/x2/{kind}_raw_{split}_x{s:g}.pkl", "rb")) for s in (1.0, 2.0)}
    es = {s: r.eval_set(s) for s in (1.0, 2.0)}
    regs = {}
    for c in cascades:
        for sig in c:
            if sig not in regs:
                regs[sig] = BoxRegressor.fit(src, aspect=aspect, seed=0, log_size_sigma=sig)
    out = {}
    for c in cascades:
        row = {}
        for s in (1.0, 2.0):
            dets = dumps[s]["raw"]
            for sig in c:
                d2 = copy.copy(det); d2.box_regressor = regs[sig]
                dets = refine_detections(d2, es[s], dets, nms_iou=proto.detection.nms_iou)
            res = ProtocolResult(str(c), proto, split=split, scale=s)
            res.add_seed(0, videos=match_videos(es[s].stems, dets, es[s].boxes, proto), patches=(), meta={})
            row[f"x{s:g}"] = round(res.mean_ap(), 4)
        print(c, row, flush=True); out[str(c)] = row
    json.dump(out, open(f"data/analysis/x2/{kind}_cascade_{split}.json", "w"), indent=1)
