"""``synthaug diagnose``: seed set + mesh + fit → report.json and report.md of what the simulation misses.

Example::

    synthaug diagnose --seed-set data/halmstad/seedsets/drone_100 --mesh ../shared/data/meshes/quadcopter.glb \\
        --params fits/drone_100_hog.json --distance hog --out results/diagnose/drone_100 \\
        --extended-fit fits/drone_100_hog_extended.json
"""

from __future__ import annotations

import argparse
import json
import sys


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import add_option

    add_option(parser, "--seed-set", aliases=["--seeds"], required=True, help="seed-set folder")
    parser.add_argument("--mesh", default="quadcopter", help="the mesh the fit used (file or built-in name)")
    add_option(parser, "--params", aliases=["--fit"], required=True,
               help="fitted capture-parameter file (synthaug fit output)")
    parser.add_argument("--distance", default="hog", help="the detector's distance (normally the fit's)")
    parser.add_argument("--out", required=True, help="output folder (report.json, report.md, plots)")
    parser.add_argument("--candidates", nargs="*", default=None, help="candidate effects (default: all 14)")
    parser.add_argument("--folds", type=int, default=5, help="cross-validation folds over seeds")
    parser.add_argument("--seed", type=int, default=0, help="seeds folds, permutations and renders")
    parser.add_argument("--alpha", type=float, default=0.01, help="family-wise significance level")
    parser.add_argument("--no-plots", action="store_true", help="write report.json/report.md without the PNG figures")
    add_option(parser, "--no-progress", aliases=["--quiet"], action="store_true",
               help="no progress lines: print nothing but the final JSON summary")
    parser.add_argument("--extended-fit", default=None, metavar="PATH",
                        help="also write the fit extended by the first finding's effect (per-seed patch units); "
                             "nothing is written when there is no candidate-effect finding")
    parser.add_argument("--gap", type=int, default=0, metavar="N",
                        help="add the gap section: real seed patches vs N random-pose synthetic samples per seed "
                             "(and vs the best-fit renders) in each detector's features: classifier two-sample "
                             "accuracy with CI, KID, most separating features (default 0: off)")
    parser.add_argument("--object-colour", type=float, nargs=3, default=None, metavar=("R", "G", "B"),
                        help="the object's known colour (three positive values of any scale, e.g. a photo of its "
                             "paint): the colour channel compares against it instead of a neutral grey object, so "
                             "a white balance can be told from the object's own colour (RGB seed sets only)")
    parser.add_argument("--gap-detector", action="append", default=[], metavar="FAMILY=CHECKPOINT",
                        help="measure the gap in this trained detector's features (hog, adaboost or cnn; "
                             "repeatable); families not given use HOG settings, random weak learners and an "
                             "untrained seeded CNN")


def _validate(args: argparse.Namespace) -> None:
    """Options and output paths checked before any work; a --distance other than the fit's is a warning."""
    import math

    from synthaug._checks import check_output_dir, check_output_file, check_seedset_dir
    from synthaug.distances.registry import check_distance
    from synthaug.params import CaptureParams

    gap_detectors(args)  # cheap, named first
    if getattr(args, "object_colour", None) is not None:
        from synthaug.diagnose.diagnosis_data import object_colour_factors

        try:
            object_colour_factors(args.object_colour)
        except ValueError as e:
            raise ValueError(f"--object-colour: {e}") from None
    if not (math.isfinite(args.alpha) and 0.0 < args.alpha < 1.0):
        raise ValueError(f"--alpha must be in (0, 1), got {args.alpha}")
    if args.folds < 2:
        raise ValueError(f"--folds must be >= 2, got {args.folds}")
    check_seedset_dir(args.seed_set)
    check_distance(args.distance)
    check_output_dir(args.out)
    if args.extended_fit:
        check_output_file(args.extended_fit, "--extended-fit")
    _, _, meta = CaptureParams.load_with_extra(args.params)  # a missing / corrupt fit is named now
    fitted = (meta.get("config") or {}).get("distance") if isinstance(meta.get("config"), dict) else None
    if isinstance(fitted, str) and fitted != args.distance:
        print(f"synthaug diagnose: warning: {args.params} was fitted with distance {fitted!r} but --distance is "
              f"{args.distance!r}; the residuals are measured in {args.distance!r} space", file=sys.stderr)


def gap_detectors(args: argparse.Namespace) -> dict[str, str]:
    """``--gap`` and ``--gap-detector FAMILY=CHECKPOINT`` checked: ``{family: checkpoint path}``."""
    from pathlib import Path

    from synthaug.diagnose.gap import FAMILIES

    gap = getattr(args, "gap", 0)
    given = getattr(args, "gap_detector", None) or []
    if gap < 0:
        raise ValueError(f"--gap must be >= 0, got {gap}")
    if given and not gap:
        raise ValueError("--gap-detector needs --gap N (N > 0 synthetic samples per seed)")
    out: dict[str, str] = {}
    for item in given:
        family, sep, path = item.partition("=")
        if not sep or family not in FAMILIES or not path:
            raise ValueError(f"--gap-detector must be FAMILY=CHECKPOINT with FAMILY in {list(FAMILIES)}, got {item!r}")
        if family in out:
            raise ValueError(f"--gap-detector: {family} given twice")
        if not Path(path).is_file():
            raise ValueError(f"--gap-detector: {path} (for {family}) is not a file")
        out[family] = path
    return out


def main(args: argparse.Namespace) -> int:
    from synthaug.diagnose.report import diagnose

    try:
        _validate(args)
        report = diagnose(args.seed_set, args.mesh, args.params, distance=args.distance, out_dir=args.out,
                          candidates=args.candidates, k=args.folds, seed=args.seed, alpha=args.alpha,
                          plots=not args.no_plots, gap=getattr(args, "gap", 0),
                          gap_detectors=gap_detectors(args) or None,
                          object_colour=getattr(args, "object_colour", None),
                          progress=None if args.no_progress else (lambda s: print(s, file=sys.stderr)))
    except (ValueError, FileNotFoundError) as e:
        print(f"synthaug diagnose: {e}", file=sys.stderr)
        return 2
    extended = None
    if args.extended_fit:
        from synthaug.diagnose.extend import extend_fit

        try:
            extended = str(extend_fit(args.params, args.seed_set, report, args.extended_fit, mesh=args.mesh))
        except ValueError as e:  # no candidate-effect finding: the report stands, no extension is written
            print(f"synthaug diagnose: --extended-fit not written: {e}", file=sys.stderr)
    print(json.dumps({"out": args.out, "significant": report["significant"],
                      "findings": [f["effect"] for f in report["findings"]], "seconds": round(report["seconds"], 1),
                      **({"extended_fit": extended} if args.extended_fit else {})}))
    return 0


if __name__ == "__main__":  # pragma: no cover
    p = argparse.ArgumentParser(prog="synthaug diagnose", description=__doc__)
    add_arguments(p)
    sys.exit(main(p.parse_args()))
