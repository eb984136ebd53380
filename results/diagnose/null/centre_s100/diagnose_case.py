"""Stop 100: one cached power-table case diagnosed exactly as ``bench_diagnose_null.py`` does, its whole report kept
(the bench keeps only the findings), its findings printed.

    PYTHONPATH=. python results/diagnose/null/centre_s100/diagnose_case.py outputs/fresh13000_gamma_alt/case_002 OUT.json
"""
import json
import sys
from pathlib import Path

import torch

torch.set_num_threads(1)
from synthaug.data.seedset import SeedSet  # noqa: E402
from synthaug.diagnose.report import diagnose  # noqa: E402

case = Path(sys.argv[1])
rep = diagnose(SeedSet.load(case / "seeds"), "quadcopter", case / "fit.json", out_dir=None, plots=False, seed=0)
Path(sys.argv[2]).write_text(json.dumps(rep, indent=1, default=str))
for f in rep["findings"]:
    print(json.dumps(f, default=str)[:1500])
