"""Refit the box regressor with scale augmentation / wider jitter; score dumped raw detections at x1 and x2."""
import pickle, sys, time, copy, json
import numpy as np, torch
from synthaug.detectors.base import load_detector
from synthaug.detectors.boxes import BoxRegressor
from synthaug.detectors.frames import VideoFrames
from synthaug.detectors.video_training import discover_videos, split_by_video
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.runner import ProtocolRunner, DataPaths
from synthaug.evaluate.videos import refine_detections, scale_frame
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.matching import match_videos

class Scaled:
    def __init__(self, src, scales): self.src, self.scales = src, scales
    def __iter__(self):
        for it in self.src:
            for s in self.scales:
                if it.boxes is None: continue
                b = np.asarray(it.boxes, np.float64).reshape(-1, 4).copy(); b[:, 2:] += b[:, :2]
                f, b2 = scale_frame(np.asarray(it.image), b, s); b2[:, 2:] -= b2[:, :2]
                yield it._replace(image=f, boxes=b2)

if __name__ == "__main__":
    torch.set_num_threads(1)
    kind = sys.argv[1]
    split = sys.argv[4] if len(sys.argv) > 4 else "test"
    det = load_detector(f"data/analysis/x2/{kind}100_s0.pt")
    proto = load_protocol(); r = ProtocolRunner(proto, "drone", DataPaths(), eval_split=split)
    vs = discover_videos(r.paths.videos_dir, r.paths.labels_dir)
    sp = split_by_video(vs, "drone", split=r.paths.split_file, seed=0)
    src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["train"], stride=15)
    bw = det.box_in_window; aspect = bw[2] / bw[3]
    dumps = {s: pickle.load(open(f"data/analysis/x2/{kind}_raw_{split}_x{s:g}.pkl", "rb")) for s in (1.0, 2.0)}
    es = {s: r.eval_set(s) for s in (1.0, 2.0)}
    import ast
    variants = eval(sys.argv[2])
    out = {}
    for name, v in variants.items():
        t0 = time.time()
        reg = BoxRegressor.fit(Scaled(src, v["scales"]), aspect=aspect, seed=0, log_size_sigma=v["sig"], shift_sigma=v.get("shift", 0.12), jitters=v.get("jit", 16))
        d2 = copy.copy(det); d2.box_regressor = reg
        row = {"fit_s": round(time.time() - t0), "samples": reg.meta["samples"], "ridge": reg.ridge}
        for s in (1.0, 2.0):
            dets = refine_detections(d2, es[s], dumps[s]["raw"], nms_iou=proto.detection.nms_iou)
            res = ProtocolResult(name, proto, split=split, scale=s)
            res.add_seed(0, videos=match_videos(es[s].stems, dets, es[s].boxes, proto), patches=(), meta={})
            row[f"x{s:g}"] = round(res.mean_ap(), 4)
        print(name, row, flush=True); out[name] = row
    json.dump(out, open(f"data/analysis/x2/{kind}_reg_variants_%s.json" % sys.argv[3] + "", "w"), indent=1)
