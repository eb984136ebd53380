"""A finer pyramid level: the tables of this folder from the runs' saved results (trains nothing).

    python results/learning_curve/drone_pyramid/combine.py

For each family and split with both runs present: the default pyramid (1.25 ... 0.41) against the same trained
detectors scored with the level 1.5625 added (``--detect-scales``), paired by training seed and video resample.
"""
from pathlib import Path

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.summary import report_table

HERE = Path(__file__).resolve().parent
RUNS = {"hog": ("hog_{split}_default", "hog_{split}_detectfine", "hog_100_seeds.json"),
        "cnn": ("cnn_{split}_default", "cnn_{split}_detectfine", "cnn_100_seeds.json"),
        "adaboost": ("adaboost_{split}_default_s012", "adaboost_{split}_detectfine_s012", "adaboost_100_seeds.json")}

if __name__ == "__main__":
    text = "# A finer pyramid level (x1.5625 added): tables\n\nAP@0.5, 100 real seeds, 3 training seeds; Δ paired.\n"
    for split in ("val", "test"):
        for fam, (a, b, name) in RUNS.items():
            pa, pb = (HERE / a.format(split=split) / name), (HERE / b.format(split=split) / name)
            if not (pa.is_file() and pb.is_file()):
                continue
            rows = {}
            for label, p in ((f"{fam}, default pyramid (6 levels, 1.25 … 0.41)", pa),
                             (f"{fam}, + level 1.5625 (scoring only)", pb)):
                r = ProtocolResult.load(p)
                r.condition = label
                rows[label] = r
            first = next(iter(rows))
            text += (f"\n## {fam}, {split} split\n\n"
                     + "".join(f"- {k}: " + ", ".join(f"seed {s} {v:.3f}" for s, v in r.per_seed_ap().items()) + "\n"
                               for k, r in rows.items())
                     + "\n" + report_table(rows, baseline=first) + "\n")
    (HERE / "tables.md").write_text(text)
    print(text)
