"""Stop 114: diagnose cached bench cases (bench_diagnose_null.py's work dirs) with this checkout's code and print
each case's findings, the frames' edge sharpness and what the defocus row's channels say.
usage: python diagnose_case.py CASE_DIR... [--json OUT]"""
import json
import sys
import time

import torch

from synthaug.diagnose.report import diagnose

torch.set_num_threads(1)
args = sys.argv[1:]
out = args[args.index("--json") + 1] if "--json" in args else None
dirs = [a for i, a in enumerate(args) if a != "--json" and (i == 0 or args[i - 1] != "--json")]
rows = []
for d in dirs:
    t = time.perf_counter()
    rep = diagnose(f"{d}/seeds", "quadcopter", f"{d}/fit.json", out_dir=None, plots=False, seed=0)
    found = [f"{f['effect']} ({f['channel']})" if f["effect"] != "unexplained"
             else "unexplained: " + ", ".join(f["structure"]) for f in rep["findings"]]
    dfc = [r for r in rep["screened"] if r["effect"] == "defocus"]
    chans = [{k: c.get(k) for k in ("channel", "gain", "significant", "frames_veto")} for c in dfc[0]["channels"]] \
        if dfc else []
    row = {"case": d, "findings": found, "seconds": time.perf_counter() - t, "defocus": chans}
    rows.append(row)
    print(json.dumps(row), flush=True)
if out:
    with open(out, "w") as f:
        json.dump(rows, f, indent=1)
