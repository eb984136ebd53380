"""Issue 15: does HOG's SVM converge on the all-frames training set? Round 0 of a runner cell, re-trained with every
``train_linear_svm`` call recorded.

Rebuilds round 0 of ``hog / all training frames`` (or of K videos) for one training seed exactly as the runner does
(``frames_training_set`` + look-alike bird crops, ``train_detector`` with the protocol's options), wraps
``synthaug.detectors.hog_dpm.train_linear_svm`` to record, per call, the positives and negatives, the objective and
its gradient norm after the call's L-BFGS budget (``max_iter`` 200), and the objective after ``--extra`` more
iterations from there: a relative drop well above 0 means the call stopped short of its optimum.

    PYTHONPATH=. python results/learning_curve/video_diversity/svm_convergence.py --seed 1 [--positive-videos K]
"""
from __future__ import annotations

import argparse
import json
import time

import torch

import synthaug.detectors.hog_dpm as H
from synthaug.detectors.training import TrainOptions, train_detector
from synthaug.detectors.training_sets import bird_hard_negatives, frames_training_set
from synthaug.detectors.video_training import discover_videos, positive_video_subset, split_by_video


def objective(x, y, w, b, cost, lam):
    margin = torch.relu(1.0 - y * (x @ w + b))
    return 0.5 * lam * (w * w).sum() + (cost * margin * margin).sum()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--positive-videos", type=int, default=None)
    ap.add_argument("--extra", type=int, default=1000)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    torch.set_num_threads(1)
    vs = discover_videos("../shared/data/halmstad/videos", "../shared/data/halmstad/labels")
    sp = split_by_video(vs, "drone", split="configs/splits/halmstad.json", seed=a.seed)
    train = sp["train"] if a.positive_videos is None else positive_video_subset(sp["train"], a.positive_videos, a.seed)
    t0 = time.perf_counter()
    d = frames_training_set(train, vs.videos_dir, vs.labels_dir, frame_step=3, seed=a.seed)
    neg = torch.cat([d["negatives"], bird_hard_negatives(sp["negative_train"], vs.videos_dir, vs.labels_dir)])
    print(f"{d['positives'].shape[0]} positives, {neg.shape[0]} negatives ({time.perf_counter() - t0:.0f} s)", flush=True)

    calls = []
    original = H.train_linear_svm

    def recorded(features, labels, *, regularization=1e-3, max_iter=200, init=None, sample_weight=None):
        w, b = original(features, labels, regularization=regularization, max_iter=max_iter, init=init,
                        sample_weight=sample_weight)
        x, y = features.double(), labels.double()
        n_pos, n_neg = int((y > 0).sum()), int((y < 0).sum())
        cost = torch.where(y > 0, 0.5 / n_pos, 0.5 / n_neg)
        wd, bd = w.double().requires_grad_(True), b.double().reshape(()).requires_grad_(True)
        f = objective(x, y, wd, bd, cost, regularization)
        gw, gb = torch.autograd.grad(f, [wd, bd])
        w2, b2 = original(features, labels, regularization=regularization, max_iter=a.extra, init=(w, b))
        f2 = float(objective(x, y, w2.double(), b2.double(), cost, regularization))
        calls.append({"positives": n_pos, "negatives": n_neg, "objective": float(f), "grad_norm": float(torch.cat([gw, gb.reshape(1)]).norm()),
                      "objective_after_extra": f2, "relative_drop": (float(f) - f2) / max(float(f), 1e-300),
                      "warm": init is not None})
        print(json.dumps(calls[-1]), flush=True)
        return w, b

    H.train_linear_svm = recorded
    t0 = time.perf_counter()
    train_detector("hog", d["positives"], neg, a.seed, box_in_window=None, mining_frames=d["mining_frames"],
                   mining_boxes=d["mining_boxes"], options=TrainOptions())
    print(f"round 0 trained in {time.perf_counter() - t0:.0f} s", flush=True)
    if a.out:
        with open(a.out, "w") as fh:
            json.dump({"seed": a.seed, "positive_videos": a.positive_videos, "calls": calls}, fh, indent=1)


if __name__ == "__main__":
    main()
