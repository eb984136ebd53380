"""Issue 20, stop 112: one row of the estimator tables (compare.py, shared.py, validate.py, gl_compare.py): the floor
by the library's rule over the 44 calibration cases, the channel's test (stop 111's compare.py) on every case, the
clean cases' spread split into seed- and case-level parts, and the specular rows named, per set of 5 in case order."""
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from compare import Z, channel_names, is_calibration, spread_parts  # noqa: E402

from synthaug.diagnose.calibration import one_sided_floor  # noqa: E402

HEADER = ("| model | converged μ±σ | full fits μ±σ | floor | clean power > floor (max) | clean seed ⊕ case sd "
          "| default named | wider named | wider k |\n|---|---|---|---|---|---|---|---|---|")


def row(label, res, default_key="specular/"):
    """The table's row of ``res`` ({case name: (pooled k, its error, seeds)}); ``default_key`` marks the default
    strength's cases in their names (the wider's: ``specular_alt/``)."""
    cal = np.array([r[0] for n, r in res.items() if is_calibration(n)])
    hand = np.array([r[0] for n, r in res.items() if "hand2000" in n])
    full = np.array([r[0] for n, r in res.items() if "null_full" in n])
    centre, floor = cal.mean(), one_sided_floor(cal, Z)
    named = {n: channel_names(*r, centre, floor) for n, r in res.items()}
    clean = [n for n in res if "_clean/" in n]
    seed, casel = spread_parts([res[n][0] for n in clean], [res[n][1] for n in clean])
    dflt = [named[n] for n in res if default_key in n]
    alt = [n for n in res if "specular_alt/" in n]
    altn = [named[n] for n in alt]
    per_set = lambda rows: "+".join(str(sum(rows[i:i + 5])) for i in range(0, len(rows), 5))  # noqa: E731
    return (f"| {label} | {hand.mean():.3f}±{hand.std(ddof=1):.3f} | {full.mean():.3f}±{full.std(ddof=1):.3f} "
            f"| {floor:.3f} | {sum(named[n] for n in clean)}/{len(clean)} "
            f"({max(res[n][0] for n in clean):.3f}) | {seed:.3f} ⊕ {casel:.3f} "
            f"| {sum(dflt)}/{len(dflt)} ({per_set(dflt)}) | {sum(altn)}/{len(altn)} ({per_set(altn)}) | "
            f"{' '.join(f'{res[n][0]:.2f}' for n in alt)} |")
