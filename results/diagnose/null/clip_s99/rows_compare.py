"""Stop 99: two sets of power-table rows (``bench_diagnose_null.py`` outputs of the same cases) side by side — per row
named first / misnamed first / missed, and every case whose findings differ.

    PYTHONPATH=. python results/diagnose/null/clip_s99/rows_compare.py BEFORE_DIR AFTER_DIR
"""
import json
import sys
from pathlib import Path


def load(d: str) -> dict:
    out = {}
    for f in sorted(Path(d).glob("*.json")):
        try:
            out[f.stem] = json.loads(f.read_text())
        except (ValueError, OSError):
            continue
    return out


def tally(row: dict) -> str:
    p = row.get("power")
    if p:
        return f"{p['named_first']}/{p['misnamed_first']}/{p['missed']}"
    return f"false alarms {row.get('false_alarms')}"


def main() -> int:
    before, after = load(sys.argv[1]), load(sys.argv[2])
    changed = 0
    for name in sorted(set(before) & set(after)):
        b, a = before[name], after[name]
        diffs = []
        for cb, ca in zip(b.get("per_case", []), a.get("per_case", [])):
            if cb["findings"] != ca["findings"]:
                diffs.append(f"  case {ca['case']}: {cb['findings']} -> {ca['findings']}")
        changed += bool(diffs)
        print(f"{name:45s} {tally(b):>16s} -> {tally(a):<16s}" + ("" if diffs else "  (every case the same)"))
        print("\n".join(diffs)) if diffs else None
    print(f"{changed} of {len(set(before) & set(after))} rows with a case that changed; "
          f"only before: {sorted(set(before) - set(after))}; only after: {sorted(set(after) - set(before))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
