"""Stop 95 (measured, not adopted unless said so in results/diagnose/README.md): can the shape of the frames' noise
level function tell an expansive tone curve (gamma > 1: var = c_i * I^s, a straight line in log-log) from shot noise
(var = a_i + sigma^2 * I, Foi et al.: curved in log-log), where the patches' tone (tone_evidence) could not (fresh
gamma 1.4 cases 0 and 3 of seed base 11000 named shot noise)? Held-out seeds (5 folds): each model's common parameter
fitted on the training seeds, the held-out seed's own level by maximum likelihood; per seed the log-likelihood of the
power law minus that of the affine model (nats per pixel); mean and t over seeds.

    PYOPENGL_PLATFORM=egl PYTHONPATH=. python results/diagnose/null/nlf_shape_s95/nlf_shape.py CASE_DIR... > OUT.txt
"""
import sys

import numpy as np
from scipy.optimize import minimize_scalar

from synthaug.diagnose.diagnosis_data import load_diagnosis_data
from synthaug.diagnose.noise import HIGH_PASS_VAR, _fit_model, _heldout_loglik
from synthaug.diagnose.screening import kfold
from synthaug.diagnose.stats import t_test


def _norm(n):
    ok = (n["signal"] > 0) & (n["var"] > 0) & (n["count"] > 0)
    return n["signal"][ok], n["var"][ok] / (HIGH_PASS_VAR * float(n.get("looks", 1.0))), n["count"][ok].astype(float)


def affine_b(nlfs, iterations=3):
    """sigma^2 of var = a_i + b I (per-seed a_i), weighted least squares as noise.shot_noise_sigma (b may be < 0)."""
    sig, var, cnt, seed = [], [], [], []
    for n in nlfs:
        s, v, c = _norm(n)
        if len(s) < 2:
            continue
        sig.append(s); var.append(v); cnt.append(c); seed.append(np.full(len(s), len(sig) - 1))
    s, v, c, g = (np.concatenate(x) for x in (sig, var, cnt, seed))
    x = np.zeros((s.size, len(sig) + 1)); x[np.arange(s.size), g] = 1.0; x[:, -1] = s
    model = v
    for _ in range(iterations):
        sw = np.sqrt(c) / np.maximum(model, 1e-12)
        coef = np.linalg.lstsq(x * sw[:, None], v * sw, rcond=None)[0]
        model = np.maximum(x @ coef, 1e-12)
    return float(coef[-1])


def loglik_affine(n, b):
    s, v, c = _norm(n)
    if len(s) < 2:
        return float("nan")
    lo = max(-b * s.min(), 0.0) + 1e-12 if b >= 0 else -b * s.max() + 1e-12

    def nll(a):
        m = a + b * s
        return float((c * 0.5 * (np.log(2 * np.pi * m) + v / m)).sum() / c.sum())
    r = minimize_scalar(nll, bounds=(lo, max(lo * 10, float(v.max()) * 10)), method="bounded")
    return -r.fun


def loglik_power(n, slope):
    s, v, c = _norm(n)
    if len(s) < 2:
        return float("nan")
    return _heldout_loglik({"signal": s, "var": v, "count": c}, slope)


for case in sys.argv[1:]:
    data = load_diagnosis_data(f"{case}/seeds", f"{case}/fit.json", "quadcopter")
    nlfs = data.noise_levels
    if nlfs is None:
        print(case, "no NLF"); continue
    folds = kfold(len(nlfs), 5, np.random.default_rng(0))
    d = np.full(len(nlfs), np.nan)
    for held in folds:
        train = [nlfs[j] for j in np.setdiff1d(np.arange(len(nlfs)), held)]
        s, b = float(_fit_model(train, "power")[0]), affine_b(train)
        for j in held:
            d[j] = loglik_power(nlfs[j], s) - loglik_affine(nlfs[j], b)
    m, t, p = t_test(d)
    print(f"{case}  power-affine {m:+.5f} nats/px  t {t:+.2f}  p {p:.2g}  slope {float(_fit_model(nlfs, 'power')[0]):.3f}"
          f"  b {affine_b(nlfs):.2e}", flush=True)
