"""Issue 20, stop 110: could any specular model be named from the distance gain? The exact highlight as the extension.

Each specular power case of base 8000 has a clean twin (``bench_diagnose_null.py --base-seed 8000`` without
``--hidden``: the same scenes, nuisances, poses and noise draws), so real - twin is the hidden highlight itself after
the camera. It is added to the model's render (w_d re-solved on real - highlight) and the per-seed held-out gain is
scored as the screening scores one (relative to the mean base distance, minus the two-parameter penalty 0.01).

    PYTHONPATH=. python results/diagnose/null/highlight_s110/oracle.py ""      # default strength
    PYTHONPATH=. python results/diagnose/null/highlight_s110/oracle.py _alt    # the wider strength
"""
import sys
import numpy as np, torch
from scipy import stats
from synthaug.data.seedset import SeedSet
from synthaug.diagnose import screening as S
from synthaug.diagnose.diagnosis_data import load_diagnosis_data, render_with, pixel_distance, pairwise_distance
suffix = sys.argv[1]
for k in range(5):
    case = f'outputs/bench_diagnose_power5_specular{suffix}/case_00{k}'
    a = SeedSet.load(f'{case}/seeds'); b = SeedSet.load(f'outputs/bench_diagnose_power5_clean/case_00{k}/seeds')
    data = load_diagnosis_data(a, f"{case}/fit.json", "quadcopter")
    d = torch.as_tensor((np.asarray(a.patches, float) - np.asarray(b.patches, float)) / 255.0)[:, None]
    syn, w = S.base_render(data)
    bp, bf = pixel_distance(data.real, syn), pairwise_distance(data, syn)
    # oracle: the model's render plus the true highlight, w_d re-solved
    a0 = render_with(data, None, w_d=torch.full((len(data),), 0.2), clamp=False).double()
    a1 = render_with(data, None, w_d=torch.full((len(data),), 0.6), clamp=False).double()
    sl = (a1 - a0) / 0.4
    y = data.real.double() - d
    wo = (0.2 + ((y - a0) * sl).flatten(1).sum(1) / (sl * sl).flatten(1).sum(1)).clamp(0, 1)
    syno = ((a0 + (wo - 0.2)[:, None, None, None] * sl) + d).clamp(0, 1).float()
    op, of = pixel_distance(data.real, syno), pairwise_distance(data, syno)
    for sp, b_, o_ in (("pixel", bp, op), ("feature", bf, of)):
        g = (b_ - o_) / b_.mean() - 0.01
        t = stats.ttest_1samp(g, 0, alternative='greater')
        print(f"{case[-28:]} {sp}: oracle gain {g.mean():+.4f} t {t.statistic:.1f} p {t.pvalue:.1e}", flush=True)
