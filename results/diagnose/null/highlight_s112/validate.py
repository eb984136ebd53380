"""Issue 20, stop 112: the models shortlisted on the stop-111 cases (shared.py, compare.py), judged on fresh sets made
after they were chosen (base seeds 15000 and 17000: 5 specular cases at each strength and 20 clean cases each), the
floor from the same 44 calibration cases. The per-set counts run over the sets in the order of the arguments.

    PYTHONPATH=. python results/diagnose/null/highlight_s112/validate.py outputs/s112_gram_calib_spec.npz \
        outputs/s112_gram_clean.npz outputs/s112_gram_v15000_spec.npz outputs/s112_gram_v17000_spec.npz \
        outputs/s112_gram_v15000_clean.npz outputs/s112_gram_v17000_clean.npz
"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import shared  # noqa: E402

shared.MODELS = {  # shortlisted before the fresh sets were made
    "per seed s,h80 (library)": (["s", "h80"], [], []),
    "h80; case amb": (["s", "h80"], [], ["amb"]),
    "h80; case amb,sm": (["s", "h80"], [], ["amb", "sm"]),
    "h80; video amb,sm": (["s", "h80"], ["amb", "sm"], []),
    "h45; per seed amb,sm": (["s", "h45", "amb", "sm"], [], []),
    "h45; per seed amb; case sm": (["s", "h45", "amb"], [], ["sm"]),
}

if __name__ == "__main__":
    shared.main()
