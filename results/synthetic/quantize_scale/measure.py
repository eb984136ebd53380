"""What the detector sees of a real object, against what it is trained on, by the object's size: exactly flat
neighbour pairs and distance to the 8-bit lattice (stop 106, issue 16).

A real training positive is ``crop_patch``'s uint8 crop at P = 40 px (rounded after resampling: on the 8-bit lattice
at every size); at test time the sliding window reads the frame through the pyramid's float resize
(``sliding.resize_image``: bilinear, antialiased when shrinking), at the pyramid scale that brings the object to the
seed patches' 28 px. A small object is read near its native pixels (scales 1.25 / 1.0: lattice values, flat areas
kept); a large one averaged down (scales <= 0.64: off the lattice, few exactly flat pairs). Synthetic positives are
float (the paper) or rounded at P (``quantize``). Per seed of a seed set: the training patch, the window the pyramid
shows of the same object, and synthetic patches drawn from the set's fit both ways (8 per seed on average, each
seed's own); means by the object's longest side. Reads ``data/runs/ingest_*`` and ``data/runs/fits`` (made by the
runner).

    PYTHONPATH=. python results/synthetic/quantize_scale/measure.py SEEDSET FIT MESH SCALES... > OUT.txt
"""
import sys

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.sliding import resize_image
from synthaug.detectors.training_sets import synthetic_positives
from synthaug.effects.camera_functional import quantize_levels

BUCKETS = ((0, 24), (24, 48), (48, 96), (96, 1e9))


def flat_share(x: np.ndarray) -> float:
    """Share of horizontally and vertically adjacent pixel pairs with exactly equal values."""
    return float(np.concatenate([(x[:, 1:] == x[:, :-1]).ravel(), (x[1:] == x[:-1]).ravel()]).mean())


def lattice_offset(x: np.ndarray) -> float:
    """Mean distance (in 8-bit levels) of the values from the nearest 8-bit level: 0 on the lattice, 0.25 uniform."""
    v = x.astype(np.float64) * 255
    return float(np.abs(v - np.round(v)).mean())


def main(seedset_dir: str, fit: str, mesh: str, scales: list[float]) -> None:
    s = SeedSet.load(seedset_dir)
    p, side = s.patch_size, s.object_fraction * s.patch_size  # the patch and the object's side in it (40, 28 px)
    margin = round((p - side) / 2)
    inner = slice(margin, p - margin)  # the object's square
    syn, idx = synthetic_positives(s, mesh, fit, 8 * len(s), seed=0, return_seed_index=True)
    synq = quantize_levels(syn)
    rows = []
    for i in range(len(s)):
        box = np.asarray(s.boxes[i], np.float64).reshape(-1, 4)[0]
        longest = float(max(box[2], box[3]))
        scale = min(scales, key=lambda f: abs(np.log(longest * f / side)))
        frame = torch.from_numpy(s.frame(i).astype(np.float32) / 255)[None, None]
        level = resize_image(frame, scale)[0, 0].numpy()
        cx, cy = (box[0] + box[2] / 2) * scale, (box[1] + box[3] / 2) * scale
        x0, y0 = int(round(cx - p / 2)), int(round(cy - p / 2))
        if x0 < 0 or y0 < 0 or x0 + p > level.shape[1] or y0 + p > level.shape[0]:
            continue
        view = level[y0:y0 + p, x0:x0 + p]
        train = s.patches[i].astype(np.float32) / 255
        mine = (idx == i)
        if not mine.any():  # no draw with this seed's capture parameters
            continue
        f = syn[torch.from_numpy(mine), 0].numpy()
        q = synq[torch.from_numpy(mine), 0].numpy()
        stats = [longest, scale]
        for a in (train, view):
            stats += [flat_share(a[inner, inner]), lattice_offset(a[inner, inner])]
        stats.append(flat_share(quantize_levels(torch.from_numpy(view[inner, inner])).numpy()))  # the level, 8-bit
        stats += [np.mean([flat_share(x[inner, inner]) for x in q]),
                  np.mean([flat_share(x[inner, inner]) for x in f]),
                  np.mean([lattice_offset(x[inner, inner]) for x in f])]
        rows.append(stats)
    r = np.array(rows)
    print(f"# {seedset_dir}: {len(r)} of {len(s)} seeds (the rest too near the frame's edge at their scale, or not "
          f"drawn); the object's {side:g} px, means per bucket")
    print("| longest side | seeds | pyramid scales | flat pairs: training patch (uint8) | test view | "
          "test view rounded | synthetic 8-bit | synthetic float | off-lattice (levels): training | test view | "
          "synthetic float |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for lo, hi in BUCKETS:
        m = (r[:, 0] >= lo) & (r[:, 0] < hi)
        if not m.any():
            continue
        b = r[m].mean(0)
        sc = "/".join(f"{v:g}" for v in sorted(set(r[m, 1]), reverse=True))
        print(f"| {lo}-{hi if hi < 1e9 else ''} px | {int(m.sum())} | {sc} | {b[2]:.3f} | {b[4]:.3f} | {b[6]:.3f} | "
              f"{b[7]:.3f} | {b[8]:.3f} | {b[3]:.3f} | {b[5]:.3f} | {b[9]:.3f} |")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3], [float(v) for v in sys.argv[4:]])
