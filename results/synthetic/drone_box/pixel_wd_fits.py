"""Each real drone fit's w_d re-solved by pixel least squares at its fitted pose (``../demo_box/resolve.py``), written
beside it as ``data/runs/fits/drone_100_seed{s}_hog_pixelwd.json`` (HOG cannot see the object's contrast sign).

    PYOPENGL_PLATFORM=egl PYTHONPATH=.:results/synthetic/demo_box python results/synthetic/drone_box/pixel_wd_fits.py  # 16 s
"""
from resolve import resolve_wd

from synthaug.data.seedset import SeedSet

for s in (0, 1, 2):
    ss = SeedSet.load(f"data/runs/ingest_drone_seed{s}/seedsets/drone_100")
    old, new = resolve_wd(ss, f"data/runs/fits/drone_100_seed{s}_hog.json", f"data/runs/fits/drone_100_seed{s}_hog_pixelwd.json")
    old, new = old.flatten(), new.flatten()
    print(f"seed set {s}: w_d fitted median {float(old.median()):.2f}, re-solved {float(new.median()):.2f}; "
          f"changed by > 0.2: {int(((old - new).abs() > 0.2).sum())} of {len(old)}")
