import sys, pickle, copy, torch
sys.path.insert(0, "results/learning_curve/drone_box_cnn/offline")
from cnn_reg import net, CNNReg
from synthaug.detectors.base import load_detector
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.runner import ProtocolRunner, DataPaths
from synthaug.evaluate.videos import refine_detections
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.matching import match_videos
if __name__ == "__main__":
    torch.set_num_threads(1)
    kind, split, saved = sys.argv[1:4]
    sd = torch.load(saved); m = net(); m.load_state_dict(sd["net"]); m.eval()
    det = load_detector(f"data/analysis/x2/{kind}100_s0.pt")
    proto = load_protocol(); r = ProtocolRunner(proto, "drone", DataPaths(), eval_split=split)
    row = {}
    for s in (1.0, 2.0):
        es = r.eval_set(s); raw = pickle.load(open(f"data/analysis/x2/{kind}_raw_{split}_x{s:g}.pkl", "rb"))["raw"]
        d2 = copy.copy(det); d2.box_regressor = CNNReg(m, sd["mean_y"])
        dets = refine_detections(d2, es, raw, nms_iou=proto.detection.nms_iou)
        res = ProtocolResult("x", proto, split=split, scale=s)
        res.add_seed(0, videos=match_videos(es.stems, dets, es.boxes, proto), patches=(), meta={})
        row[f"x{s:g}"] = round(res.mean_ap(), 4)
    print(kind, split, saved, row)
