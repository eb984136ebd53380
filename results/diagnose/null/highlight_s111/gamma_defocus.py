"""Issue 20, stop 111: why 13000's gamma 1.4 case 2 is named defocus — defocus screened on the case and on its clean
twin, alone and on top of gamma (at the frames' reading 1.338 and at the truth 1.4).

    PYTHONPATH=. python results/diagnose/null/highlight_s111/gamma_defocus.py
"""
import torch

from synthaug.data.seedset import SeedSet
from synthaug.diagnose.diagnosis_data import load_diagnosis_data
from synthaug.diagnose.screening import CANDIDATE_GRIDS, n_screening_tests, screen_candidates

torch.set_num_threads(1)
N_TESTS = n_screening_tests(list(CANDIDATE_GRIDS))
for case, gammas in (("outputs/fresh13000_gamma_alt/case_002", (None, 1.338, 1.4)),
                     ("outputs/fresh13000_clean/case_002", (None,))):
    data = load_diagnosis_data(SeedSet.load(f"{case}/seeds"), f"{case}/fit.json", "quadcopter")
    for g in gammas:
        r = screen_candidates(data, ["defocus"], given=None if g is None else {"gamma": {"gamma_g": g}},
                              n_tests=N_TESTS)[0]
        px = next(c for c in r["channels"] if c["channel"] == "distance:pixel")
        print(f"{case} given gamma {g}: defocus pixel gain {px['gain']:.4f} (floor {px['floor']:.4f}, p_adj "
              f"{px['p_adjusted']:.1e}), significant {r['significant']}", flush=True)
