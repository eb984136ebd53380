"""Issue 20, specular (stop 42): does the object residual's upper tail separate a hidden highlight from clean cases?

On cached power-run and clean cases (bench_diagnose_null.py workdirs), per seed: the residual real - fitted render
(the diagnosis's base render, w_d re-solved) inside the eroded coverage; its skewness, its 95/5 % quantile asymmetry
over its MAD, and the real and rendered patches' upper and lower spreads (95 % - median, median - 5 %) over the
object's contrast. Appends one JSON line per case to /tmp/sp/out.jsonl and prints the case means.

    PYTHONPATH=. python results/diagnose/null/specular_tails.py outputs/bench_diagnose_null/case_0?? \\
        outputs/bench_diagnose_power5_specular{,_alt}/case_00?   # about 8 s a case
"""
import sys, json, glob, numpy as np, torch
from scipy import ndimage
from synthaug.data.seedset import SeedSet
from synthaug.diagnose import screening as S
from synthaug.diagnose.diagnosis_data import load_diagnosis_data

def stats(case):
    seeds = SeedSet.load(f"{case}/seeds")
    data = load_diagnosis_data(seeds, f"{case}/fit.json", "quadcopter")
    syn, w = S.base_render(data)
    real = data.real[:, 0].numpy(); syn = syn[:, 0].numpy(); cov = data.coverage[:, 0].numpy()
    bg = data.background[:, 0].numpy()
    out = []
    for i in range(len(real)):
        m = ndimage.binary_erosion(cov[i] > 0.5, iterations=1)
        if m.sum() < 12:
            m = cov[i] > 0.5
        if m.sum() < 6:
            continue
        r = (real[i] - syn[i])[m]
        contrast = np.abs((syn[i] - bg[i])[m]).mean() + 1e-3
        med = np.median(r); mad = 1.4826 * np.median(np.abs(r - med)) + 1e-4
        q95, q05 = np.quantile(r, 0.95), np.quantile(r, 0.05)
        out.append(dict(skew=float(((r - r.mean())**3).mean() / (r.std()**3 + 1e-9)),
                        asym=float(((q95 - med) - (med - q05)) / mad),
                        maxpos=float((r.max() - med) / mad), maxneg=float((med - r.min()) / mad),
                        top=float((q95 - med) / contrast), bot=float((med - q05) / contrast),
                        realtop=float((np.quantile(real[i][m],0.95)-np.median(real[i][m]))/contrast),
                        syntop=float((np.quantile(syn[i][m],0.95)-np.median(syn[i][m]))/contrast),
                        realbot=float((np.median(real[i][m])-np.quantile(real[i][m],0.05))/contrast),
                        synbot=float((np.median(syn[i][m])-np.quantile(syn[i][m],0.05))/contrast),
                        realmax=float((real[i][m].max()-np.median(real[i][m]))/contrast),
                        synmax=float((syn[i][m].max()-np.median(syn[i][m]))/contrast)))
    return out

for case in sys.argv[1:]:
    o = stats(case)
    d = {k: np.array([x[k] for x in o]) for k in o[0]}
    summ = {k: (float(v.mean()), float(v.std() / np.sqrt(len(v)))) for k, v in d.items()}
    nu = json.load(open(f"{case}/case.json"))["key"]["nuisances"]
    print(json.dumps({"case": case, "mean": {k: v[0] for k, v in summ.items()}, "se": {k: v[1] for k, v in summ.items()}, "per_seed": {k: v.tolist() for k, v in d.items()}}), file=open("/tmp/sp/out.jsonl", "a"))
    print(case, json.dumps({k: round(v[0], 3) for k, v in summ.items()}), "t_asym", round(summ['asym'][0]/summ['asym'][1],2),
          "ks", round(nu["specular_ks"],3), "sm", nu["normal_smoothing_px"], flush=True)
