"""Issue 20, stop 113: run.sh's diagnosis times before and after, per row (median over its 5 cases x 2 repeats) and
overall, and whether every case's findings are the same.

    python results/diagnose/speed_s113/summary.py > results/diagnose/speed_s113/summary.json
"""
import json
import pathlib

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent


def main():
    out, alls = {}, {"before": [], "after": []}
    for row in ("gamma_alt", "sharpening_alt", "lens_distortion_alt"):
        r = {}
        for which in ("before", "after"):
            runs = [json.loads((HERE / f"{row}_{which}_{k}.json").read_text()) for k in (1, 2)]
            t = [c["diagnosis_seconds"] for d in runs for c in d["per_case"]]
            alls[which] += t
            found = [[c["findings"] for c in d["per_case"]] for d in runs]
            r[which] = {"median_s": round(float(np.median(t)), 1), "max_s": round(float(np.max(t)), 1),
                        "findings": found[0], "same_findings_both_repeats": found[0] == found[1]}
        r["same_findings_before_after"] = r["before"]["findings"] == r["after"]["findings"]
        r["speedup_median"] = round(r["before"]["median_s"] / r["after"]["median_s"], 2)
        out[row] = r
    out["all_cases"] = {w: {"median_s": round(float(np.median(t)), 1), "max_s": round(float(np.max(t)), 1),
                            "n": len(t)} for w, t in alls.items()}
    out["command"] = "BASE=<checkout of c0a3f34, the code before> bash results/diagnose/speed_s113/run.sh"
    out["conditions"] = ("1 thread, base seed 13000's cached cases, 60 seeds each; a second single-thread job "
                         "(exposure_s113/dump.py) ran on the other core throughout, before and after alike")
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
