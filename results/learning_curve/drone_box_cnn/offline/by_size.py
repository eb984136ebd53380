"""Per-size AP of the ridge map vs the CNN map on fixed detectors' raw detections (one split)."""
import sys, pickle, copy, torch
sys.path.insert(0, "results/learning_curve/drone_box_cnn/offline")
from cnn_reg import net, CNNReg
from synthaug.detectors.base import load_detector
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.runner import ProtocolRunner, DataPaths
from synthaug.evaluate.videos import refine_detections
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.matching import match_videos
from synthaug.evaluate.summary import report_table
if __name__ == "__main__":
    torch.set_num_threads(1)
    kind, split = sys.argv[1:3]
    sd = torch.load("data/analysis/x2/cnnreg_0.35_8.pt"); m = net(); m.load_state_dict(sd["net"]); m.eval()
    det = load_detector(f"data/analysis/x2/{kind}100_s0.pt")
    proto = load_protocol(); r = ProtocolRunner(proto, "drone", DataPaths(), eval_split=split, log=lambda m: None)
    for s in (1.0, 2.0):
        es = r.eval_set(s); raw = pickle.load(open(f"data/analysis/x2/{kind}_raw_{split}_x{s:g}.pkl", "rb"))["raw"]
        rows = {}
        class Mean:
            def __init__(self, a, b): self.a, self.b = a, b
            def refine(self, image, boxes):
                from synthaug.detectors.boxes import decode_deltas
                if image.dim() == 2: image = image[None, None]
                if boxes.shape[0] == 0: return boxes
                return decode_deltas(boxes.float(), 0.5 * (self.a.predict(image, boxes).float() + self.b.predict(image, boxes).float()))
        for name, reg in (("ridge", det.box_regressor), ("cnn map", CNNReg(m, sd["mean_y"])), ("mean of both", Mean(det.box_regressor, CNNReg(m, sd["mean_y"])))):
            d2 = copy.copy(det); d2.box_regressor = reg
            dets = refine_detections(d2, es, raw, nms_iou=proto.detection.nms_iou)
            res = ProtocolResult(name, proto, split=split, scale=s)
            res.add_seed(0, videos=match_videos(es.stems, dets, es.boxes, proto), patches=(), meta={})
            rows[name] = res
        print(f"### {kind} {split} x{s:g}\n" + report_table(rows, baseline="ridge").split("\n\nProtocol")[0], flush=True)
