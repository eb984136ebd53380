"""Exposure's absorbed w_d against the metered frame brightness, within videos, under three permutation statistics
(Pearson of the logs, Spearman, Pearson of the values), on cached power-table cases (stop 39 of the README).

usage: PYTHONPATH=. python results/diagnose/null/absorption_statistics.py outputs/bench_diagnose_power5_exposure/case_00{0,1,2,3,4}
Prints each case's r and Bonferroni-adjusted p (x39, the diagnosis's count for the full candidate list) for each
statistic.
"""
import sys

import numpy as np
import torch

from synthaug.diagnose.diagnosis_data import load_diagnosis_data
from synthaug.diagnose.residuals import seed_groups, seed_metadata
from synthaug.diagnose.screening import CANDIDATE_GRIDS, base_render, n_screening_tests
from synthaug.diagnose.stats import permutation_correlation

torch.set_num_threads(1)
n_tests = n_screening_tests(list(CANDIDATE_GRIDS))  # the full candidate list: 39, as in the diagnosis
for d in sys.argv[1:]:
    data = load_diagnosis_data(f"{d}/seeds", f"{d}/fit.json", "quadcopter")
    _, w0 = base_render(data)
    w, b, g = w0.numpy().astype(float), seed_metadata(data)["frame_brightness"], seed_groups(data)
    out = []
    for name, method, x, y in (("pearson_log", "pearson", np.log(b), np.log(w)), ("spearman", "spearman", b, w),
                               ("pearson", "pearson", b, w)):
        r, p = permutation_correlation(x, y, np.random.default_rng(0), 99_999, g, method=method)
        out.append(f"{name} r {r:+.2f} p_adj {min(1.0, p * n_tests):.4f}")
    print(d, " | ".join(out), flush=True)
