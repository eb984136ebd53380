"""One table of stored ProtocolResult JSONs (e.g. two runner invocations' conditions), paired against the first.

    PYTHONPATH=. python results/learning_curve/drone_v2/pair.py BASELINE.json OTHER.json [...] [--out MD]
"""
import argparse
from pathlib import Path

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.summary import report_table

ap = argparse.ArgumentParser()
ap.add_argument("results", nargs="+")
ap.add_argument("--out", default=None)
a = ap.parse_args()
res = {}
for f in a.results:
    r = ProtocolResult.load(f)
    res[r.condition] = r
text = report_table(res, baseline=next(iter(res)))
print(text)
if a.out:
    Path(a.out).write_text(text + "\n")
