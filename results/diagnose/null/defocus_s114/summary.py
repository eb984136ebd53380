"""Stop 114: the rows rerun with the frames' blur check beside the same rows before it, case by case, with the frames'
edge sharpness (the sharpening frame statistic) and the bound a blur of the frame must pass.
usage: PYTHONPATH=. python results/diagnose/null/defocus_s114/summary.py [BEFORE_DIR=...] -> summary.txt"""
import glob
import json
import os
from pathlib import Path

from synthaug.diagnose.calibration import gain_centre, gain_upper

HERE = Path(__file__).parent
# the rows before the check: before/BASE (the code before, f24a0a5, on the same cases, this machine: run_before.sh and
# the first rows of run.sh), else the power tables' stored rows
BEFORE = {"13000": ["results/diagnose/null/highlight_s112/video_light/13000",
                    "results/diagnose/null/highlight_s111/13000", "results/diagnose/null/objects_s100/13000",
                    "results/diagnose/null/centre_s100/13000", "results/diagnose/null/clip_s99/13000"],
          "8000": ["results/diagnose/null/highlight_s112/video_light/8000", "results/diagnose/null/highlight_s111/8000",
                   "results/diagnose/null/objects_s100/8000", "results/diagnose/null/centre_s100/8000",
                   "results/diagnose/null/periodic_s96/8000", "results/diagnose/null"],
          "11000": ["results/diagnose/null/highlight_s112/video_light/11000",
                    "results/diagnose/null/highlight_s111/11000", "results/diagnose/null/objects_s100/11000",
                    "results/diagnose/null/centre_s100/11000", "results/diagnose/null/periodic_s96/11000",
                    "results/diagnose/null/fresh11000"]}
c, up = gain_centre("sharpening", "frame"), gain_upper("sharpening", "frame")
print(f"frames' edge sharpness: clean centre {c:.4f}, clean upper {up:.4f}, a blur of the frame below {2 * c - up:.4f}")
for base in ("8000", "11000", "13000", "15000", "17000"):  # 15000, 17000: fresh sets (stop 112's clean)
    for f in sorted(glob.glob(str(HERE / base / "power5_*.json")) + glob.glob(str(HERE / base / "clean_gray.json"))):
        name = os.path.basename(f)
        after = json.load(open(f))
        dirs = [str(HERE / "before" / base)] + BEFORE.get(base, [])
        before = next((json.load(open(os.path.join(d, name))) for d in dirs if os.path.exists(os.path.join(d, name))),
                      None)
        pw, ratio = after["power"], after["null_distributions"]["screen:sharpening:frame"]["gain"]["values"]
        if pw is None:
            print(f"\n{base} clean: false alarms {after['false_alarms']}/{after['cases']} "
                  f"(before: {None if before is None else before['false_alarms']})")
        else:
            sigmas = ("; settings " + str([s.get("defocus_sigma") for s in pw["settings_named_first"]])
                      if pw["hidden"] == "defocus" else "")
            print(f"\n{base} {name[7:-5]}: named first {pw['named_first']}/5, misnamed {pw['misnamed_first']}, "
                  f"missed {pw['missed']}{sigmas}")
        for i, case in enumerate(after["per_case"]):
            old = None if before is None else before["per_case"][i]["findings"]
            print(f"  case {i}: edges {ratio[i]:.4f}  {case['findings']}"
                  + ("" if old is None or old == case["findings"] else f"  (before: {old})   CHANGED"))
