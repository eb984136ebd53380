"""Issue 20, stop 110: highlight-amplitude estimators compared on the 8000 power cases (before the channel was built).

MODE=wd (default): per seed, joint least squares of the albedo w_d and the amplitude k of a specular lobe (exponent
SHIN) — the estimator adopted as ``screening.highlight_strength``; MODE=sh: with a first-order spherical-harmonics
shading basis (n_x, n_y, n_z) beside them (absorbs light-direction mismatch, and part of the highlight with it).
Prints the weighted mean k, the intercept of k against w_d (confounded: the joint fit's errors in k and w_d are
anti-correlated) and the truth's mean ks.

    MODE=wd SHIN=45 PYTHONPATH=. python results/diagnose/null/highlight_s110/estimators.py \
        outputs/bench_diagnose_power5_specular{,_alt}/case_00? outputs/bench_diagnose_power5_clean/case_0[01]?
"""
import sys, os
import numpy as np, torch
import synthaug.effects.paper as P
from synthaug.data.seedset import SeedSet
from synthaug.diagnose import screening as S
from synthaug.diagnose.diagnosis_data import load_diagnosis_data, render_with
MODE = os.environ.get("MODE", "wd")   # wd | sh
SH = float(os.environ.get("SHIN", "30"))
orig = P.Fx.diffuse_material
J = {"j": None}
def basis_material(normals, coverage, w_d, *, light_dir=None, ambient=0.4):
    j = J["j"]
    if j is None:
        return orig(normals, coverage, w_d, light_dir=light_dir, ambient=ambient)
    on = (coverage > 0).to(normals.dtype)
    return on if j == 0 else normals[:, j - 1:j] * on
P.Fx.diffuse_material = basis_material

def wls(x, y, W):
    X = np.stack([np.ones(len(x)), x], 1)
    beta = np.linalg.lstsq(X * np.sqrt(W)[:, None], y * np.sqrt(W), rcond=None)[0]
    res = y - X @ beta
    s2 = (W * res ** 2).sum() / (len(x) - 2)
    cov = s2 * np.linalg.inv((X * W[:, None]).T @ X)
    return beta, np.sqrt(np.diag(cov))

for case in sys.argv[1:]:
    seeds = SeedSet.load(f"{case}/seeds")
    data = load_diagnosis_data(seeds, f"{case}/fit.json", "quadcopter")
    n = len(data)
    a0 = render_with(data, None, w_d=torch.full((n,), 0.2), clamp=False).double()
    a1 = render_with(data, None, w_d=torch.full((n,), 0.6), clamp=False).double()
    Sl = (a1 - a0) / 0.4
    ext = S.extension_values(data, "specular", {"specular_ks": 1.0, "specular_shininess": SH})
    H = render_with(data, ext, w_d=torch.full((n,), 0.2), clamp=False).double() - a0
    cols = [Sl, H]
    if MODE == "sh":
        J["j"] = "x"
        for j in (1, 2, 3):
            J["j"] = j
            cols.append(render_with(data, None, w_d=torch.ones(n), clamp=False).double() - 0 * a0)
        J["j"] = None
        # the basis renders include the background composite: subtract the zero-object render
        J["j"] = 0
        on = render_with(data, None, w_d=torch.zeros(n), clamp=False).double()
        J["j"] = None
        cols = cols[:2] + [c - on for c in cols[2:]]
    A = torch.stack(cols, -1).flatten(1, 3)  # (N, P, K)
    y = (data.real.double() - a0).flatten(1)
    k_est, k_se, w_est = np.zeros(n), np.zeros(n), np.zeros(n)
    for i in range(n):
        Ai, yi = A[i].numpy(), y[i].numpy()
        sol, *_ = np.linalg.lstsq(Ai, yi, rcond=None)
        res = yi - Ai @ sol
        s2 = (res ** 2).sum() / (len(yi) - Ai.shape[1])
        cov = s2 * np.linalg.pinv(Ai.T @ Ai)
        k_est[i], k_se[i], w_est[i] = sol[1], np.sqrt(max(cov[1, 1], 1e-12)), 0.2 + sol[0]
    W = 1 / k_se ** 2
    beta, se = wls(w_est, k_est, W)
    wm = (W * k_est).sum() / W.sum()
    ks = np.mean([rec["truth"]["hidden"].get("specular", {}).get("specular_ks", 0.0) for rec in seeds.records])
    print(f"{case[-30:]}: wmean k {wm:+.3f}; intercept {beta[0]:+.3f} (t {beta[0]/se[0]:.1f}) slope {beta[1]:+.3f}; "
          f"median k {np.median(k_est):+.3f}; true {ks:.2f}", flush=True)
