"""renders_seed0.png: seed 0's 100-seed drone set, one row each (24 patches, 40 px): real seed patches; the shape
cell's synthetic positives (no critic); rendered blob distractors (two rows; ``probe.distractors``, one per seed).

    PYTHONPATH=. PYOPENGL_PLATFORM=egl python results/synthetic/adaboost_distractors/picture.py
"""
import sys
import tempfile
from pathlib import Path

import torch
from torchvision.utils import save_image

from synthaug.data.seedset import SeedSet
from synthaug.detectors.training_sets import real_positives, synthetic_positives

sys.path.insert(0, str(Path(__file__).resolve().parent))
import probe  # noqa: E402  (this folder's)

ss = SeedSet.load("data/runs/ingest_drone_seed0/seedsets/drone_100")
fit = "data/runs/fits/drone_100_seed0_hog_quadcopter.json"
with tempfile.TemporaryDirectory() as tmp:
    d = probe.distractors(ss, fit, 1, 0, tmp)
s = synthetic_positives(ss, probe.MESH, fit, 100, seed=2, **{**probe.SHAPE_CELL, "realism_keep": 1.0})
idx = torch.arange(0, 96, 4)
save_image(torch.cat([real_positives(ss)[:100][idx], s[idx], d[idx], d[idx + 2]]),
           Path(__file__).resolve().parent / "renders_seed0.png", nrow=24)
