import pickle, sys, numpy as np, torch
from torchvision.ops import box_iou, box_convert
from synthaug.detectors.base import load_detector
from synthaug.detectors.boxes import BoxRegressor
kind = sys.argv[1] if len(sys.argv) > 1 else "hog"
det = load_detector(f"data/analysis/x2/{kind}100_s0.pt")
reg = det.box_regressor
def xyxy(b): return box_convert(torch.as_tensor(np.asarray(b, np.float64).reshape(-1, 4), dtype=torch.float32), "xywh", "xyxy")
for s in (1.0, 2.0):
    d = pickle.load(open(f"data/analysis/x2/{kind}_raw_x{s:g}.pkl", "rb"))
    rows = []
    for dv, bv in zip(d["raw"], d["boxes"]):
        for dets, gts in zip(dv, bv):
            if gts is None or len(gts) == 0 or len(dets) == 0: continue
            g = xyxy(gts); p = xyxy(dets[:, :4])
            iou = box_iou(p, g)
            for j in range(g.shape[0]):
                cand = (iou[:, j] > 0.05).nonzero().flatten()
                if len(cand) == 0: continue
                k = int(cand[np.argmax(dets[cand.numpy(), 4])])  # best-scored overlapping
                gw, gh = float(g[j, 2] - g[j, 0]), float(g[j, 3] - g[j, 1])
                pw = float(p[k, 2] - p[k, 0])
                rows.append((max(gw, gh), pw / max(gw, gh), float(iou[k, j]), gw / gh))
    a = np.array(rows)
    print(f"x{s:g}: {len(a)} drones with an overlapping det; longest side median {np.median(a[:,0]):.1f}; "
          f"window/longest median {np.median(a[:,1]):.2f} q10 {np.quantile(a[:,1],.1):.2f} q90 {np.quantile(a[:,1],.9):.2f}; "
          f"IoU median {np.median(a[:,2]):.2f}, share IoU>=0.5 {np.mean(a[:,2]>=0.5):.2f}")
    for lo, hi in ((0, 24), (24, 48), (48, 96), (96, 999)):
        m = (a[:, 0] >= lo) & (a[:, 0] < hi)
        if m.sum(): print(f"   {lo}-{hi}: n {m.sum()}, window/longest {np.median(a[m,1]):.2f}, IoU>=0.5 {np.mean(a[m,2]>=0.5):.2f}")
