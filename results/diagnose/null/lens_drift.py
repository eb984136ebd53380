"""Lens-distortion power cases against their scene drift: is lens_distortion named first where the frames can show it?

The lens's frame channel (``frame_pattern.radial_flow``) reads k off the scene's motion between a frame and its
background frame and needs a shift of at least ``MIN_DRIFT_PX``; the nuisance model moves each seed's scene by a
uniform draw up to the case's ``background_drift_px``. Reads the lens rows of each folder given (a later folder's file
of the same name wins, as ``power_table.py`` does) and splits the cases at that drift.

    PYTHONPATH=. python results/diagnose/null/lens_drift.py results/diagnose/null results/diagnose/null/fresh11000 \
        results/diagnose/null/periodic_s96/13000
"""
import json
import sys
from pathlib import Path

from synthaug.diagnose.frame_pattern import MIN_DRIFT_PX

latest = {}
for folder in sys.argv[1:]:
    for f in sorted(Path(folder).glob("power5_lens_distortion*.json")):
        latest[(folder, f.name)] = f
count = {True: [0, 0], False: [0, 0]}  # drift reaches MIN_DRIFT_PX -> [named first, cases]
print("| set | k1 | case | largest drift (px) | first finding | findings |")
print("|---|---|---|---|---|---|")
for (folder, name), f in latest.items():
    d = json.load(open(f))
    k1 = d["hidden_settings"]["lens_distortion"]["distortion_k1"]
    for c in d["per_case"]:
        drift = float(c["nuisances"]["background_drift_px"])
        first = c["findings"][0] if c["findings"] else "nothing"
        named = first.startswith("lens_distortion")
        count[drift >= MIN_DRIFT_PX][0] += named
        count[drift >= MIN_DRIFT_PX][1] += 1
        print(f"| {d['base_seed']} | {k1:+g} | {c['case']} | {drift:.3f} | {first} | {'; '.join(c['findings'][1:])} |")
for reach, (named, n) in sorted(count.items(), reverse=True):
    print(f"\nlargest drift {'>=' if reach else '<'} {MIN_DRIFT_PX} px: lens distortion named first in {named} of {n}")
