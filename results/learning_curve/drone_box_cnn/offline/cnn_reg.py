"""A small CNN box regressor on the context crops (raw gray pixels), vs the ridge-on-HOG regressor."""
import pickle, sys, time, copy, json, math
import numpy as np, torch, torch.nn as nn
from torchvision.ops import box_convert, roi_align
from synthaug.detectors.base import load_detector
from synthaug.detectors.boxes import BoxRegressor, jitter_boxes, encode_deltas, decode_deltas
from synthaug.detectors.frames import VideoFrames
from synthaug.detectors.video_training import discover_videos, split_by_video
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.runner import ProtocolRunner, DataPaths
from synthaug.evaluate.videos import refine_detections
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.matching import match_videos

SIZE, CTX = 32, 2.0
def crops(image, boxes):
    cx, cy = 0.5 * (boxes[:, 0] + boxes[:, 2]), 0.5 * (boxes[:, 1] + boxes[:, 3])
    half = 0.5 * CTX * torch.maximum(boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1])
    rois = torch.stack([torch.zeros_like(cx), cx - half, cy - half, cx + half, cy + half], 1)
    c = roi_align(image.float(), rois, (SIZE, SIZE), spatial_scale=1.0, sampling_ratio=2, aligned=True)
    m = c.mean((1, 2, 3), keepdim=True); s = c.std((1, 2, 3), keepdim=True) + 0.02
    return (c - m) / s

class CNNReg:
    def __init__(self, net, mean_y): self.net, self.mean_y = net, mean_y
    def predict(self, image, boxes):
        with torch.no_grad(): return self.net(crops(image, boxes.float())) + self.mean_y
    def refine(self, image, boxes):
        if image.dim() == 2: image = image[None, None]
        if boxes.shape[0] == 0: return boxes
        return decode_deltas(boxes.float(), self.predict(image, boxes))

def net():
    return nn.Sequential(nn.Conv2d(1, 16, 3, padding=1), nn.BatchNorm2d(16), nn.ReLU(), nn.MaxPool2d(2),
                         nn.Conv2d(16, 32, 3, padding=1), nn.BatchNorm2d(32), nn.ReLU(), nn.MaxPool2d(2),
                         nn.Conv2d(32, 64, 3, padding=1), nn.BatchNorm2d(64), nn.ReLU(), nn.MaxPool2d(2),
                         nn.Flatten(), nn.Linear(64 * 16, 64), nn.ReLU(), nn.Linear(64, 4))

if __name__ == "__main__":
    torch.set_num_threads(1)
    kind, split, sig, epochs = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
    scales = eval(sys.argv[5]) if len(sys.argv) > 5 else (1.0,)
    torch.manual_seed(0)
    saved = sys.argv[6] if len(sys.argv) > 6 else None
    det = load_detector(f"data/analysis/x2/{kind}100_s0.pt")
    proto = load_protocol(); r = ProtocolRunner(proto, "drone", DataPaths(), eval_split=split)
    vs = discover_videos(r.paths.videos_dir, r.paths.labels_dir)
    sp = split_by_video(vs, "drone", split=r.paths.split_file, seed=0)
    src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["train"], stride=15)
    bw = det.box_in_window; aspect = bw[2] / bw[3]
    gen = torch.Generator().manual_seed(0)
    if saved:
        sd = torch.load(saved); m = net(); m.load_state_dict(sd["net"]); m.eval(); mean_y = sd["mean_y"]; epochs = 0
    X, Y, G = [], [], []
    t0 = time.time()
    from synthaug.evaluate.videos import scale_frame
    for it in ([] if saved else src):
        if it.boxes is None or np.asarray(it.boxes).size == 0: continue
        for sc in scales:
            b = np.asarray(it.boxes, np.float64).reshape(-1, 4).copy(); b[:, 2:] += b[:, :2]
            f, b = scale_frame(np.asarray(it.image), b, sc)
            img = torch.as_tensor(f).float().div(255).reshape(1, 1, *f.shape[-2:])
            g = torch.as_tensor(b, dtype=torch.float32)
            g = g[(g[:, 2] > g[:, 0]) & (g[:, 3] > g[:, 1])]
            p, idx = jitter_boxes(g, 32, aspect=aspect, generator=gen, log_size_sigma=sig)
            if not len(p): continue
            X.append(crops(img, p)); Y.append(encode_deltas(p, g[idx])); G += [it.video] * len(p)
    if saved: X = [torch.zeros(1, 1, SIZE, SIZE)]; Y = [torch.zeros(1, 4)]; G = ["a"]
    X, Y = torch.cat(X), torch.cat(Y); G = np.array(G)
    print("samples", len(X), "in", round(time.time() - t0), "s", flush=True)
    vids = sorted(set(G)); rng = np.random.default_rng(0); hold = set(rng.choice(vids, len(vids) // 5, replace=False))
    tr = torch.as_tensor(~np.isin(G, list(hold))); te = ~tr
    if not saved: mean_y = Y[tr].mean(0)
    if not saved: m = net(); opt = torch.optim.AdamW(m.parameters(), 2e-3, weight_decay=1e-4)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, 3e-3, total_steps=epochs * (int(tr.sum()) // 256 + 1))
    Xtr, Ytr = X[tr], Y[tr] - mean_y
    for ep in range(epochs):
        m.train(); perm = torch.randperm(len(Xtr), generator=gen)
        for i in range(0, len(perm), 256):
            j = perm[i:i + 256]
            xb = Xtr[j]; yb = Ytr[j].clone()
            flip = torch.rand(len(j), generator=gen) < 0.5  # horizontal flip: dx changes sign
            xb = torch.where(flip[:, None, None, None], xb.flip(-1), xb); yb[flip, 0] = -yb[flip, 0]
            loss = nn.functional.smooth_l1_loss(m(xb), yb, beta=0.1)
            opt.zero_grad(); loss.backward(); opt.step(); sched.step()
        m.eval()
        with torch.no_grad():
            e = ((m(X[te]) + mean_y - Y[te]) ** 2).mean().item()
        print(f"epoch {ep} held-out video mse {e:.4f} (no regression {((Y[te]-mean_y)**2).mean().item():.4f}) {time.time()-t0:.0f}s", flush=True)
    dumps = {s: pickle.load(open(f"data/analysis/x2/{kind}_raw_{split}_x{s:g}.pkl", "rb")) for s in (1.0, 2.0)}
    row = {}
    for s in (1.0, 2.0):
        es = r.eval_set(s)
        d2 = copy.copy(det); d2.box_regressor = CNNReg(m, mean_y)
        dets = refine_detections(d2, es, dumps[s]["raw"], nms_iou=proto.detection.nms_iou)
        res = ProtocolResult("cnnreg", proto, split=split, scale=s)
        res.add_seed(0, videos=match_videos(es.stems, dets, es.boxes, proto), patches=(), meta={})
        row[f"x{s:g}"] = round(res.mean_ap(), 4)
    print("CNN regressor", sig, scales, epochs, row, flush=True)
    if not saved: torch.save({"net": m.state_dict(), "mean_y": mean_y}, f"data/analysis/x2/cnnreg_{sig}_{epochs}.pt")
