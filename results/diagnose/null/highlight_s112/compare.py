"""Issue 20, stop 112: the highlight estimator with the shading nuisances' regressors (gram.py's columns), compared
offline as stop 111's compare.py does (the library's floor rule and the channel's test on every cached case).

    PYTHONPATH=. python results/diagnose/null/highlight_s112/compare.py outputs/s112_gram_calib_spec.npz \
        outputs/s112_gram_clean.npz
"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from table import HEADER, row  # noqa: E402

from compare import case_pooled, load_all  # noqa: E402  (stop 111's)

BASE = ["s", "h80"]
EXTRA = {
    "h80 (library)": [],
    "+lx,ly": ["lx", "ly"],
    "+sm": ["sm"],
    "+amb": ["amb"],
    "+lx,ly,sm": ["lx", "ly", "sm"],
    "+lx,ly,amb": ["lx", "ly", "amb"],
    "+lx,ly,sm,amb": ["lx", "ly", "sm", "amb"],
    "+sm,amb": ["sm", "amb"],
    "+lx,ly,sm,amb,gx,gy": ["lx", "ly", "sm", "amb", "gx", "gy"],
}


def main():
    ci, cases = load_all(sys.argv[1:])
    print(HEADER)
    for h in ("h80", "h45"):
        for name, extra in EXTRA.items():
            res = case_pooled(cases, ci, ["s", h] + extra, [0, 1] + [0] * len(extra))
            label = name if h == "h80" else name.replace("h80 (library)", "h45") + " (h45)"
            print(row(label, res), flush=True)


if __name__ == "__main__":
    main()
