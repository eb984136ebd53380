"""AdaBoost's mining rule: the tables of this folder, from cached cells and saved results only (trains nothing).

    python results/learning_curve/adaboost_mining/combine.py [test|val] [WORK]

Rows (100 real seeds, AdaBoost, protocol halmstad_v1; paired by training seed and video resample):
- 100 rounds, the default rule (fewest validation FPs, no patience): drone_v6's cells (`../drone_v6/adaboost/`; test only);
- 300 rounds, the default rule: stop 33's cells (`../adaboost_capacity/test_r300/`, seeds 1 and 0; on val seed 2);
- 300 rounds, `--mining-select ap --mining-patience 1`: this folder's cells, read from the cell cache.
"""
import sys
from pathlib import Path

from synthaug.detectors.training import TrainOptions
from synthaug.evaluate.cells import CellCache
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.runner import Condition, DataPaths, ProtocolRunner
from synthaug.evaluate.summary import report_table

HERE = Path("results/learning_curve/adaboost_mining")
NEW = "adaboost / 100 seeds, 300 rounds, mining by validation AP, patience 1"

if __name__ == "__main__":
    split = sys.argv[1] if len(sys.argv) > 1 else "test"
    work = sys.argv[2] if len(sys.argv) > 2 else "data/runs"
    proto = load_protocol()
    cache = CellCache(Path(work) / "cells", read_only=True)
    opts = TrainOptions(ada_rounds=300, mining_select="ap", mining_patience=1)
    runner = ProtocolRunner(proto, "drone", DataPaths(work_dir=work), cache, options=opts, scale_check=False,
                            patches=split == "test", eval_split=split, log=lambda m: None)
    c100 = Condition("adaboost / 100 seeds", "adaboost", seed_count=100)
    rows: dict[str, ProtocolResult] = {}
    if split == "test":
        old100 = ProtocolResult.load(HERE.parent / "drone_v6" / "adaboost" / "adaboost_100_seeds.json")
        old300 = ProtocolResult.load(HERE.parent / "adaboost_capacity" / "test_r300" / "adaboost_100_seeds.json")
        rows["adaboost / 100 seeds, 100 rounds, fewest validation FPs (drone_v6)"] = old100
        rows["adaboost / 100 seeds, 300 rounds, fewest validation FPs (stop 33)"] = old300
    else:
        for name, folder in (("100 rounds, fewest validation FPs (stop 33, seed 0)", "val_r100_seed0"),
                             ("300 rounds, fewest validation FPs (stop 33, seed 2)", "val_r300_seed2")):
            rows[f"adaboost / 100 seeds, {name}"] = ProtocolResult.load(
                HERE.parent / "adaboost_capacity" / folder / "adaboost_100_seeds.json")
    res = runner.run(c100, [0, 1, 2])
    if 1.0 in res:
        rows[NEW] = res[1.0]
        rows[NEW].condition = NEW
    first = next(iter(rows))
    text = (f"## AdaBoost, 100 real seeds: the mining rule ({split} split)\n\n"
            f"Baseline of the paired column: the first row. Per seed AP@0.5:\n\n"
            + "".join(f"- {k}: " + ", ".join(f"seed {s} {v:.3f}" for s, v in r.per_seed_ap().items()) + "\n"
                      for k, r in rows.items())
            + "\n" + report_table(rows, baseline=first) + "\n")
    if split == "test" and NEW in rows:
        text += ("\n### Against 300 rounds with the default rule (the mining rule alone; common seeds 0 and 1)\n\n"
                 + report_table({k: rows[k] for k in list(rows)[1:]}, baseline=list(rows)[1]) + "\n")
    (HERE / f"tables_{split}.md").write_text(text)
    print(text)
