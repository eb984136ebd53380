"""The first 24 seeds of a seed set with a median background: patch with the labelled box (green) and its measured
object / label ratio, and |patch − background| below it.

    PYTHONPATH=. python results/learning_curve/label_convention/figure.py SEEDSET_DIR OUT.png
"""
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from convention import object_extent  # noqa: E402

from synthaug.data.seedset import SeedSet  # noqa: E402

ss = SeedSet.load(sys.argv[1])
idx = [i for i, r in enumerate(ss.records) if r.get("background_method") == "median"][:24]
fig, axs = plt.subplots(4, 12, figsize=(24, 8))
for ax in axs.flat:
    ax.set_axis_off()
for j, i in enumerate(idx):
    p, b = np.asarray(ss.patches[i]).astype(float), np.asarray(ss.backgrounds[i]).astype(float)
    ax = axs[(j // 12) * 2, j % 12]
    ax.imshow(p, cmap="gray", vmin=0, vmax=255)
    n, side = p.shape[0], 0.7 * p.shape[0]
    ax.add_patch(plt.Rectangle(((n - side) / 2 - 0.5, (n - side) / 2 - 0.5), side, side, fill=False, ec="lime"))
    ext = object_extent(p, b, k=4.0, floor=6.0)
    ax.set_title(f"{ss.records[i]['video']} {'' if ext is None else '%.2f' % (max(ext[2] - ext[0], ext[3] - ext[1]) / side)}",
                 fontsize=8)
    axs[(j // 12) * 2 + 1, j % 12].imshow(np.abs(p - b), cmap="magma")
plt.tight_layout()
plt.savefig(sys.argv[2], dpi=60)
