"""Issue 20, stop 112: gram_light.py's oracle (the template and the diffuse shading at each video's true light) against
the library's template at the model's light, judged as stop 111's compare.py judges (the library's pooling, floor
rule over the 44 calibration cases and test). Per-set counts in the order of the arguments' specular cases.

    PYTHONPATH=. python results/diagnose/null/highlight_s112/gl_compare.py outputs/s112_gl_calib.npz \
        outputs/s112_gl_clean.npz outputs/s112_gl_spec.npz
"""
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from compare import Z, channel_names, is_calibration, pooled, spread_parts  # noqa: E402

from synthaug.diagnose.calibration import one_sided_floor  # noqa: E402

MODELS = {"s,h80 at the model's light (library)": ([0, 1], "yy"), "s,h45 at the model's light": ([0, 2], "yy"),
          "sL,h80L at the video's true light": ([3, 4], "yyL"), "sL,h45L at the video's true light": ([3, 5], "yyL")}


def per_seed(case, idx, yy_key):
    G, b, yy = case["G"][:, idx][:, :, idx], case["b"][:, idx], case[yy_key]
    ks, vs = [], []
    for i in range(len(b)):
        if G[i][1, 1] < 1e-8 or np.linalg.cond(G[i]) > 1e10:
            continue
        gi = np.linalg.inv(G[i])
        beta = gi @ b[i]
        ks.append(beta[1])
        vs.append(max((yy[i] - b[i] @ beta) / (int(case["npix"]) - 2), 1e-12) * gi[1, 1])
    return np.array(ks), np.array(vs)


def main():
    cases = []
    for p in sys.argv[1:]:
        d = np.load(p)
        cases += [{"name": str(c), **{k: d[f"{i}:{k}"] for k in ("G", "b", "yy", "yyL", "npix")}}
                  for i, c in enumerate(d["cases"])]
    print("| model | converged μ±σ | full fits μ±σ | floor | clean > floor (max) | clean seed ⊕ case sd "
          "| default named | wider named | wider k |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, (idx, yk) in MODELS.items():
        res = {c["name"]: (*pooled(*per_seed(c, idx, yk), "mean"), len(per_seed(c, idx, yk)[0])) for c in cases}
        cal = np.array([r[0] for n, r in res.items() if is_calibration(n)])
        hand = np.array([r[0] for n, r in res.items() if "hand2000" in n])
        full = np.array([r[0] for n, r in res.items() if "null_full" in n])
        centre, floor = cal.mean(), one_sided_floor(cal, Z)
        named = {n: channel_names(*r, centre, floor) for n, r in res.items()}
        clean = [n for n in res if "_clean/" in n]
        seed, casel = spread_parts([res[n][0] for n in clean], [res[n][1] for n in clean])
        dflt = [named[n] for n in res if "specular_default/" in n]
        alt = [n for n in res if "specular_alt/" in n]
        altn = [named[n] for n in alt]
        per_set = lambda rows: "+".join(str(sum(rows[i:i + 5])) for i in range(0, len(rows), 5))  # noqa: E731
        print(f"| {name} | {hand.mean():.3f}±{hand.std(ddof=1):.3f} | {full.mean():.3f}±{full.std(ddof=1):.3f} "
              f"| {floor:.3f} | {sum(named[n] for n in clean)}/{len(clean)} ({max(res[n][0] for n in clean):.3f}) "
              f"| {seed:.3f} ⊕ {casel:.3f} | {sum(dflt)}/{len(dflt)} ({per_set(dflt)}) "
              f"| {sum(altn)}/{len(altn)} ({per_set(altn)}) | {' '.join(f'{res[n][0]:.2f}' for n in alt)} |")


if __name__ == "__main__":
    main()
