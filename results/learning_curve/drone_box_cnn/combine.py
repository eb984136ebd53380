"""Tables of the CNN box regressor's runs, from cached cells only (read-only cache).

    python results/learning_curve/drone_box_cnn/combine.py all DETECTOR [WORK]
        AP(all training frames) - AP(100 seeds) at x1, paired. The 100-seed cells were scored with the x2 / x0.75
        scale check (`run.sh`), the all-frames cells without it (`run_all.sh`, --no-scale-check: the scored scales
        are part of a cell's key, the training does not depend on them), so each is read with its own runner.
    python results/learning_curve/drone_box_cnn/combine.py box-model DETECTOR [WORK]
        The CNN box map against the ridge map at x1, 100 seeds, paired: the ridge cells are the 100-seed cells
        recomputed on this machine (stop 27's `results/synthetic/drone_v1/run_hog_12seeds.sh` (c) for HOG, stop 28's
        `run_stop28.sh` (c) for the CNN; --no-scale-check, --no-patches), the CNN-map cells `run.sh`'s.
"""
import sys
from pathlib import Path

from synthaug.detectors.training import TrainOptions
from synthaug.evaluate.cells import CellCache
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.runner import Condition, DataPaths, ProtocolRunner, write_learning_curve
from synthaug.evaluate.summary import report_table

HERE = Path("results/learning_curve/drone_box_cnn")

if __name__ == "__main__":
    what, kind = sys.argv[1], sys.argv[2]
    work = sys.argv[3] if len(sys.argv) > 3 else "data/runs"
    proto, paths = load_protocol(), DataPaths(work_dir=work)
    cache = CellCache(Path(work) / "cells", read_only=True)

    def runner(**kw) -> ProtocolRunner:
        return ProtocolRunner(proto, "drone", paths, cache, log=lambda m: None, **kw)

    c100 = Condition(f"{kind} / 100 seeds", kind, seed_count=100)
    call = Condition(f"{kind} / all training frames", kind, seed_count=None, all_frames=True, frame_step=3)
    if what == "all":
        rows = {}
        for r, c in ((runner(scale_check=True), c100), (runner(scale_check=False), call)):
            for wb in (False, True):
                res = r.run(c, [0, 1, 2], window_boxes=wb)
                if 1.0 in res:
                    rows[res[1.0].condition] = res[1.0]
        write_learning_curve({kind: rows}, HERE / f"{kind}_all", baseline_count=100)
        print((HERE / f"{kind}_all" / "learning_curve.md").read_text())
    elif what == "box-model":
        rows = {}
        for label, r in ((f"{kind} / 100 seeds, ridge box map",
                          runner(options=TrainOptions(box_model="ridge"), scale_check=False, patches=False)),
                         (f"{kind} / 100 seeds, CNN box map", runner(options=TrainOptions(box_model="cnn"), scale_check=True)),
                         (f"{kind} / 100 seeds, ensemble box map",
                          runner(options=TrainOptions(box_model="ensemble"), scale_check=True))):
            res = r.run(c100, [0, 1, 2])
            if 1.0 in res:
                rows[label] = res[1.0]
        text = f"## {kind}: box map, x1\n\n" + report_table(rows, baseline=f"{kind} / 100 seeds, ridge box map") + "\n"
        (HERE / f"{kind}_box_model.md").write_text(text)
        print(text)
    else:
        sys.exit(f"unknown table {what!r}: all | box-model")
