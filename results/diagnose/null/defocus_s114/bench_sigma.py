"""Stop 114: benchmarks/bench_diagnose_null.py with the hidden defocus at another sigma than its realistic default
(the low end of its realistic range, 0.7 frame px): does the frames' edge sharpness still read blurrier than every
clean frame there?  usage: python bench_sigma.py SIGMA <bench_diagnose_null.py arguments, --hidden defocus>"""
import runpy
import sys
from pathlib import Path

from synthaug.diagnose.reference_camera import settings

sigma = float(sys.argv.pop(1))
lo, hi = settings.REALISTIC_RANGES["defocus"]["defocus_sigma"]
if not lo <= sigma <= hi:
    raise SystemExit(f"sigma {sigma} outside the realistic range {lo}-{hi}")
settings.REALISTIC_STRENGTHS["defocus"] = {"defocus_sigma": sigma}
sys.argv[0] = str(Path(__file__).resolve().parents[4] / "benchmarks" / "bench_diagnose_null.py")
runpy.run_path(sys.argv[0], run_name="__main__")
