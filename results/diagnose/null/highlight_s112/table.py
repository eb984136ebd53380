"""Issue 20, stop 112: one row of the estimator tables (compare.py, shared.py, validate.py, gl_compare.py): the floor
by the library's rule over the 44 calibration cases, the channel's test (stop 111's compare.py) on every case, the
clean cases' spread split into seed- and case-level parts, and the specular rows named, per set of 5 in case order."""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from compare import judged, spread_parts  # noqa: E402

HEADER = ("| model | converged μ±σ | full fits μ±σ | floor | clean power > floor (max) | clean seed ⊕ case sd "
          "| default named | wider named | wider k |\n|---|---|---|---|---|---|---|---|---|")


def row(label, res, default_key="specular/"):
    """The table's row of ``res`` ({case name: (pooled k, its error, seeds)}); ``default_key`` marks the default
    strength's cases in their names (the wider's: ``specular_alt/``)."""
    j = judged(res, default_key)
    hand, full, clean = j["hand"], j["full"], j["clean"]
    seed, casel = spread_parts([res[n][0] for n in clean], [res[n][1] for n in clean])
    return (f"| {label} | {hand.mean():.3f}±{hand.std(ddof=1):.3f} | {full.mean():.3f}±{full.std(ddof=1):.3f} "
            f"| {j['floor']:.3f} | {j['clean_named']}/{len(clean)} "
            f"({max(res[n][0] for n in clean):.3f}) | {seed:.3f} ⊕ {casel:.3f} "
            f"| {j['default']} | {j['wider']} | {' '.join(f'{res[n][0]:.2f}' for n in j['alt'])} |")
