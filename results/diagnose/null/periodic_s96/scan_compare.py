"""Stop 96: per stored row, how many cases had a significant periodic_* measure before (the stored bench output's
null distribution count) and now (run_scan.sh's output): the rows whose reports the band can change.

    PYTHONPATH=. python results/diagnose/null/periodic_s96/scan_compare.py SCAN_JSON STORED_DIR [STORED_DIR...]
"""
import json
import sys
from pathlib import Path


def main() -> int:
    scan = json.loads(Path(sys.argv[1]).read_text())["fresh"]
    stored = {}
    for d in sys.argv[2:]:
        for f in Path(d).glob("*.json"):
            try:
                stored.setdefault(f.stem, json.loads(f.read_text()))
            except (ValueError, OSError):
                continue
    moved = 0
    for group, g in sorted(scan.items()):
        row = group.replace("bench_diagnose_", "").replace("fresh11000_", "power5_").replace("fresh12000_", "")
        old = stored.get(row, {}).get("null_distributions", {})
        line = []
        for name in ("periodic_rows", "periodic_columns"):
            now = sum(bool(c[f"residual:{name}"]["significant"]) for c in g["cases"])
            before = (old.get(f"residual:{name}") or {}).get("significant")
            moved += before is None or now != before
            line.append(f"{name} {before} -> {now}")
        print(f"{group:45s} {len(g['cases'])} cases  " + "; ".join(line))
    print("rows whose count moved or has no stored count:", moved)
    return 0


if __name__ == "__main__":
    sys.exit(main())
