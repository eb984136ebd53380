"""AP@0.5 by the object's size (the protocol's buckets), 8-bit against float synthetic positives, per training seed,
from stored cells (stop 106). Each argument: ``LABEL=ROUNDED_GLOB,FLOAT_GLOB`` (one training seed's two cells);
``--names=A,B`` names the two cells of each pair otherwise (default ``8-bit,float``; stop 107's ``../rounding_parts``).

    PYTHONPATH=. python results/synthetic/quantize_scale/by_size.py "drones 100, seed 0=A*.json,B*.json" ... > OUT.md
"""
import glob
import sys

from synthaug.evaluate.results import ProtocolResult


def buckets(pattern: str) -> tuple[dict[str, float], dict[str, int], float]:
    paths = glob.glob(pattern)
    if len(paths) != 1:
        sys.exit(f"{pattern!r}: {len(paths)} files, want 1")
    r = ProtocolResult.load(paths[0])
    p = r.protocol
    return ({b.label: r.mean_ap(p.main_iou, b) for b in p.size_buckets},
            {b.label: r.n_objects(b) for b in p.size_buckets}, r.mean_ap(p.main_iou))


def main(args: list[str]) -> None:
    a, b = "8-bit", "float"
    if args and args[0].startswith("--names="):
        a, b = args.pop(0).split("=", 1)[1].split(",")
    rows, labels, counts = [], [], {}
    for arg in args:
        name, pair = arg.split("=", 1)
        rounded, flt = (buckets(g) for g in pair.split(","))
        labels += [k for k in rounded[1] if k not in labels]
        counts.setdefault(name.split(",")[0], rounded[1])
        rows.append((name, rounded, flt))
    print(f"| cell pair | AP@0.5 {a} / {b} | " + " | ".join(f"{k}: {a} / {b} (Δ)" for k in labels) + " |")
    print("|---|---|" + "---|" * len(labels))
    for name, q, f in rows:
        cells = [f"{q[0][k]:.3f} / {f[0][k]:.3f} ({f[0][k] - q[0][k]:+.3f})" if q[1][k] else "–" for k in labels]
        print(f"| {name} | {q[2]:.3f} / {f[2]:.3f} | " + " | ".join(cells) + " |")
    print("\nTest objects per bucket: " + "; ".join(f"{c}: " + ", ".join(f"{k} {n[k]}" for k in labels)
                                                  for c, n in counts.items()))


if __name__ == "__main__":
    main(sys.argv[1:])
