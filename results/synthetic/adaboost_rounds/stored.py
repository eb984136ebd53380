"""The AdaBoost detectors the runner stored for the 100-seed drone cells (data/runs/cells/detectors): real only and
the synthetic cells of ../adaboost_wl_critic/ (the pose cell, the shape cell), read by this folder's scripts."""
import glob
import json
import os


def stored_detectors(seeds=()) -> list[tuple[int, str, str]]:
    """``(training seed, cell, checkpoint)`` of every stored AdaBoost detector of 100 drone seeds (those of
    ``seeds`` only when given), in the order of their cache files; cell ``"real"``, ``"pose"`` or ``"shape"``."""
    out = []
    for f in sorted(glob.glob("data/runs/cells/detectors/*.json")):
        ident = json.load(open(f))["identity"]
        seed, c = ident["seed"], ident["condition"]
        if c.get("kind") != "adaboost" or c.get("seed_count") != 100 or not os.path.exists(f[:-5] + ".pt") \
                or (seeds and seed not in seeds):
            continue
        cell = "real" if not c.get("synthetic_ratio") else ("shape" if c.get("shape_variation") else "pose")
        out.append((seed, cell, f[:-5] + ".pt"))
    return out
