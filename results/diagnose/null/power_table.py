"""Issue 20's power table from the power5_*.json runs (run_power5.sh): per candidate, how often the hidden effect is
named first and significant, misnamed, or missed over 5 fresh nuisance-varied cases, with Wilson 95 % intervals.

    python results/diagnose/null/power_table.py   # from the repository root; prints a Markdown table
    python results/diagnose/null/power_table.py results/diagnose/null/paint_s93   # another folder's rows
    python results/diagnose/null/power_table.py A B   # A's rows, each replaced by B's row of the same name if any
"""

from __future__ import annotations

import json
import sys
from collections import Counter
from pathlib import Path

COLOUR_EFFECTS = {"chromatic_aberration", "white_balance", "haze"}  # judged on colour cases (gray rows kept for reference)
from synthaug.diagnose import null_floors  # noqa: E402

rows = ["| hidden | strength | data | floors | named first | misnamed first | missed | Wilson 95 % (named) | what was said |",
        "|---|---|---|---|---|---|---|---|---|"]
tot = Counter()
ok_by_effect: dict[str, list[bool]] = {}


def judged(floors: dict[str, float], colour: bool) -> dict[str, float]:
    """The floors a run is judged by: a gray run has no colour channel, so its floors are current when the others
    are."""
    return {k: v for k, v in floors.items() if colour or not k.endswith(":distance:colour")}


folders = [Path(a) for a in sys.argv[1:]] or [Path("results/diagnose/null")]
latest = {f.name: f for folder in folders for f in sorted(folder.glob("power5_*.json"))}  # a later folder's row wins
for f in (latest[name] for name in sorted(latest)):
    d = json.loads(f.read_text())
    p = d["power"]
    said = Counter(x for c in d["per_case"] for x in (c["findings"] or ["nothing"]))
    lo, hi = p["wilson95"]
    colour = bool(d.get("colour"))
    settings = (d.get("hidden_settings") or {}).get(p["hidden"])
    if settings is None:  # runs before --strength: the realistic default
        from synthaug.diagnose.reference_camera.settings import REALISTIC_STRENGTHS

        settings = REALISTIC_STRENGTHS[p["hidden"]]
    strength = ", ".join(f"{k} {v}" for k, v in settings.items())
    # the floors the run used: the current null_floors.py's, or an earlier calibration's (a row not rerun since)
    current = judged((d.get("floors_in_use") or {}).get("screen") or {}, colour) == judged(null_floors.SCREEN, colour)
    rows.append(f"| {p['hidden']} | {strength} | {'colour' if colour else 'gray'} | {'current' if current else 'earlier'} | "
                f"{p['named_first']}/{d['cases']} | {p['misnamed_first']} | {p['missed']} | "
                f"{lo:.2f}–{hi:.2f} | {', '.join(f'{k} ×{v}' for k, v in said.most_common())} |")
    if (p["hidden"] in COLOUR_EFFECTS) != colour:
        continue
    ok = p["named_first"] >= 0.8 * d["cases"] and p["misnamed_first"] <= 0.1 * d["cases"]
    tot.update(named=p["named_first"], wrong=p["misnamed_first"], missed=p["missed"], cases=d["cases"], runs=1)
    ok_by_effect.setdefault(p["hidden"], []).append(ok)
print("\n".join(rows))
both = sorted(e for e, oks in ok_by_effect.items() if len(oks) >= 2 and all(oks))
some = sorted(e for e, oks in ok_by_effect.items() if any(oks) and e not in both)
print(f"\nJudged ({' / '.join(sorted(COLOUR_EFFECTS))} on colour cases, the others on gray): {len(ok_by_effect)} "
      f"candidates, {tot['runs']} (candidate, strength) runs, {tot['cases']} cases: named first {tot['named']}, misnamed "
      f"{tot['wrong']}, missed {tot['missed']}. 'Named >= 80 %, misnamed <= 10 %' at every strength measured (>= 2): "
      f"{len(both)} of {len(ok_by_effect)} ({', '.join(both)}); at one strength only: {', '.join(some) or 'none'}")
