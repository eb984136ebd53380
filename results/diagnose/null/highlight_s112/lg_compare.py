"""Issue 20, stop 112: light_grid.py's template at each video's estimated light against the library's at the model's
light, on the corrected reference camera's specular rows (outputs/s112M_*), judged as the other tables (table.py).

    PYTHONPATH=. python results/diagnose/null/highlight_s112/lg_compare.py outputs/s112_lg_calib_spec.npz \
        outputs/s112_lg_clean.npz
"""
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from gl_compare import load_cases, print_rows  # noqa: E402

MODELS = {"s,h80 at the model's light (library)": ([0, 1], "yy"),
          "sE,h80E at each video's estimated light": ([2, 3], "yyE")}


def main():
    cases = load_cases(sys.argv[1:], ("G", "b", "yy", "yyE", "npix", "tilt_deg"))
    print_rows(cases, MODELS)
    tilts = np.concatenate([c["tilt_deg"] for c in cases])
    share = ", ".join(f"{t:.0f}° {np.mean(np.round(tilts) == t):.0%}" for t in (0, 15, 30))
    print(f"\nestimated tilts over all seeds: {share}")


if __name__ == "__main__":
    main()
