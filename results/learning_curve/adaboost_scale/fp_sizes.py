"""Sizes of the false positives that out-rank the drones, from a saved ProtocolResult (no detection is rerun).

For each training seed: the detections pooled over the test videos, best first, down to the one at which recall
reaches 0.3; the false positives among them binned by box size in x1 pixels (box size / the result's scale).

usage: python results/learning_curve/adaboost_scale/fp_sizes.py RESULT.json [RESULT.json ...]
"""
import json
import sys

import numpy as np


def load(f, seed):
    d = json.load(open(f))
    S, T, Z, G = [], [], [], []
    for v in d["seeds"][seed]["videos"]:
        S += v["scores"]; T += v["tp"][0]; Z += v["det_size"]; G += v["gt_size"]
    return np.array(S), np.array(T), np.array(Z), np.array(G), d["scale"], list(d["seeds"])


for f in sys.argv[1:]:
    for seed in load(f, next(iter(json.load(open(f))["seeds"])))[5]:
        S, T, Z, G, sc, _ = load(f, seed)
        o = np.argsort(-S)
        S, T, Z = S[o], T[o], Z[o]
        k = int(np.searchsorted(np.cumsum(T), len(G) * 0.3))
        fp = T[:k] == 0
        hist = np.histogram(Z[:k][fp] / sc, [0, 16, 24, 32, 48, 64, 1000])[0]
        print(f"{f.split('/')[-1]} seed {seed}: {len(G)} drones, {k} detections to recall 0.3, {fp.sum()} FPs; "
              f"FP box size (x1 px) <16 / 16-24 / 24-32 / 32-48 / 48-64 / >=64: {' / '.join(map(str, hist))}; "
              f"median TP size {np.median(Z[:k][~fp] / sc):.1f}")
