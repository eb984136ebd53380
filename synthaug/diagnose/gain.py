"""AP gain of an accepted extension on the real test videos (issue 6, item 3, last step).

Trains the HOG detector of the paper's Table 1 ("ours": real seed patches +
``r`` synthetic patches per real one, the ratio chosen on validation by
``fig11_ratio``, same negatives, mining frames and budgets) twice per
training seed — synthetic patches from the BASE fit, and from the fit
EXTENDED by the diagnosis's accepted effect (:func:`~synthaug.diagnose.extend.extend_fit`)
— and scores both on the test videos. Both arms draw the same poses,
backgrounds and noise fields (same dataset seed); they differ only by the
added effect. Cells are cached like the experiments' (an interrupted run
resumes).

Usage::

    python -m synthaug.diagnose.gain --class drone --report results/diagnose/drone_100/report.json \\
        --params results/paper/fits/drone_100_hog.json --training-seeds 0 1 2 --use-top-screened \\
        --out results/diagnose/drone_100
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import torch

from synthaug._checks import add_option

__all__ = ["run_gain", "main"]

DEFAULT_MESH = {"drone": "../shared/data/meshes/quadcopter.glb",
                "airplane": "../shared/data/meshes/twin_prop_airplane.glb"}
# Table 1's evaluation settings (results/paper/README.md)
MAX_VAL_VIDEOS = {"drone": 10, "airplane": 8}
SCALES = {"airplane": (1.25, 1.0, 0.8, 0.64, 0.51, 0.41, 0.33, 0.26)}


def _synthetic_build(ctx: Any, n: int, ratio: float, fit: Path) -> Callable[[], dict[str, Any]]:
    """``ExperimentContext.synthetic_build`` with an explicit fit file (same seeds, counts and negatives).

    The seeds' frame geometry is passed to the generator, so position-aware effects (vignetting, the JPEG
    grid, ...) act as in the diagnosis; the paper's effects do not read it (the base arm is Table 1's).
    """
    from synthaug.diagnose.reference_camera import seed_geometry
    from synthaug.detectors.training_sets import synthetic_positives

    def build() -> dict[str, Any]:
        d = ctx.real_build(n)()
        count = int(round(ratio * len(ctx.seedset(n))))
        syn = synthetic_positives(ctx.seedset(n), ctx.mesh, fit, count, seed=ctx.seed + 2,
                                  seed_geometry=seed_geometry(ctx.seedset(n)))
        d["positives"] = torch.cat([d["positives"], syn])
        return d

    return build


def _setting_tag(effect: str, setting: dict[str, float]) -> str:
    return effect + "".join(f"_{k}{v:g}" for k, v in sorted(setting.items()))


def run_gain(
    class_name: str,
    report: str | Path,
    fit: str | Path,
    out_dir: str | Path,
    *,
    n_seeds: int = 100,
    training_seeds: Sequence[int] = (0, 1, 2),
    ratio: float | None = None,
    use_top_screened: bool = False,
    effect: str | None = None,
    cells: str | Path | None = None,
    seedsets: str | Path = "data/halmstad/seedsets",
    mesh: str | None = None,
    stride_k: int = 15,
    detector: str = "hog",
    log: Callable[[str], None] = print,
    extended_fit: str | Path | None = None,
) -> dict[str, Any]:
    """Base vs extended fit: test AP of ``detector`` trained on real + synthetic, per training seed.

    Args:
        class_name: ``"drone"`` or ``"airplane"``.
        report: the diagnosis ``report.json`` on the seed set ``<class>_<n_seeds>`` and ``fit``.
        fit: the base fit (Table 1's ``<class>_<n>_hog.json``).
        out_dir: where ``extended_fit.json``, ``gain.json`` and ``gain.md`` go.
        n_seeds: the seed set's size.
        training_seeds: detector training seeds (each also seeds the negatives and the synthetic set).
        ratio: synthetic per real (default: the validation choice in ``results/paper/<class>/chosen_ratio.json``).
        use_top_screened: without an effect finding, extend with the top-screened candidate.
        effect: extend with this screened candidate instead (its row in the report's ``screened`` list).
        cells: cell cache (default ``<out_dir>/cells.json``).
        seedsets, mesh, stride_k: data, mesh (default per class) and test frame stride (Table 1: 15).
        detector: detector family (Table 1's HOG by default).
        extended_fit: compare ``fit`` with this already fitted file instead (e.g. a refit with a model
            extension); ``report``, ``use_top_screened`` and ``effect`` are then not used (``report`` may
            be None) and the cells are tagged with the effects it adds to ``fit``.

    Returns:
        the numbers written to ``gain.json``.
    """
    if class_name not in DEFAULT_MESH and mesh is None:
        raise ValueError(f"no default mesh for class {class_name!r}; give mesh")
    if not training_seeds:
        raise ValueError("training_seeds is empty")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fit = Path(fit)
    mesh = mesh or DEFAULT_MESH[class_name]
    if ratio is None:
        chosen = Path("results/paper") / class_name / "chosen_ratio.json"
        if not chosen.is_file():
            raise ValueError(f"no ratio given and no validation choice in {chosen}")
        ratio = float(json.loads(chosen.read_text())[detector])
    seedset_dir = Path(seedsets) / f"{class_name}_{n_seeds}"
    ext, ext_fit, tag = _extension(report, fit, out, seedset_dir, mesh, effect=effect,
                                   use_top_screened=use_top_screened, extended_fit=extended_fit)
    log(f"extension: {ext} -> {ext_fit}")

    per_seed: dict[int, dict[str, Any]] = {}
    shared_eval: dict[str, Any] = {}
    t_all = time.perf_counter()
    for s in training_seeds:
        per_seed[int(s)] = _seed_gain(int(s), shared_eval, class_name=class_name, out=out, seedsets=Path(seedsets),
                                      mesh=mesh, fit=fit, ext_fit=ext_fit, tag=tag, n_seeds=n_seeds, ratio=ratio,
                                      stride_k=stride_k, detector=detector, log=log, cells=cells)
        log(f"seed {s}: base {per_seed[int(s)]['base']:.3f} extended {per_seed[int(s)]['extended']:.3f}")
    gains = np.array([v["gain"] for v in per_seed.values()])
    numbers = {
        "class": class_name, "detector": detector, "n_seeds": n_seeds, "ratio": ratio, "stride_k": stride_k,
        "base_fit": str(fit), "extended_fit": str(ext_fit), "extension": ext, "report": str(report),
        "per_seed": per_seed,
        "mean": {k: float(np.mean([v[k] for v in per_seed.values()]))
                 for k in ("base", "extended", "base_iou03", "extended_iou03", "gain")},
        "gain_sd": float(gains.std(ddof=1)) if len(gains) > 1 else None,
        "seconds_this_run": round(time.perf_counter() - t_all, 1),
    }
    from synthaug.params import atomic_write_text

    atomic_write_text(out / "gain.json", json.dumps(numbers, indent=1) + "\n")
    atomic_write_text(out / "gain.md", _markdown(numbers))
    return numbers


def _extension(report: str | Path | None, fit: Path, out: Path, seedset_dir: Path, mesh: str, *,
               effect: str | None, use_top_screened: bool, extended_fit: str | Path | None
               ) -> tuple[dict[str, Any], Path, str]:
    """The extension compared with ``fit``: ``(description, extended fit file, cell tag)``.

    A given ``extended_fit`` is used as it is; otherwise the report's finding (or ``effect``'s screened row,
    or the top-screened candidate) extends ``fit`` into ``out/extended_fit.json``.
    """
    from synthaug.diagnose.extend import extend_fit, select_extension

    if extended_fit is not None:
        ext_fit = Path(extended_fit)
        if not ext_fit.is_file():
            raise FileNotFoundError(f"no extended fit {ext_fit}")
        eff_of = lambda f: list(json.loads(Path(f).read_text())["effects"])  # noqa: E731
        added = [e for e in eff_of(ext_fit) if e not in eff_of(fit)]
        ext = {"effect": "+".join(added) or ext_fit.stem, "setting": {}, "source": f"fitted file {ext_fit}",
               "significant": None}
        return ext, ext_fit, "fit_" + ext["effect"]
    chosen: Any = report
    if effect is not None:
        rep = json.loads(Path(report).read_text())
        rows = [r for r in rep.get("screened", []) if r.get("effect") == effect]
        if not rows:
            raise ValueError(f"{effect!r} was not screened in {report}; screened: "
                             f"{[r.get('effect') for r in rep.get('screened', [])]}")
        chosen = rows[0]
    ext = select_extension(chosen, use_top_screened=use_top_screened)
    tag = _setting_tag(ext["effect"], ext["setting"]) + "_wdr"  # w_d scaled by the effect's re-solved ratio
    ext_fit = out / "extended_fit.json"
    extend_fit(fit, seedset_dir, chosen, ext_fit, use_top_screened=use_top_screened, mesh=mesh)
    return ext, ext_fit, tag


def _seed_gain(seed: int, shared_eval: dict[str, Any], *, class_name: str, out: Path, seedsets: Path, mesh: str,
               fit: Path, ext_fit: Path, tag: str, n_seeds: int, ratio: float, stride_k: int, detector: str,
               log: Callable[[str], None], cells: str | Path | None) -> dict[str, Any]:
    """Test AP of the base and the extended arm for one training seed (``shared_eval``: the decoded test
    videos, filled by the first seed and reused)."""
    from synthaug.evaluate.context import ExperimentContext

    # one context per training seed, as Table 1's runs (the negatives are drawn with the seed)
    ctx = ExperimentContext(out_dir=out, class_name=class_name, seedsets_dir=seedsets, mesh=mesh,
                            fits_dir=fit.parent, stride_k=stride_k, val_stride_k=30,
                            max_val_videos=MAX_VAL_VIDEOS.get(class_name), scales=SCALES.get(class_name),
                            seed=seed, log=log, cells_path=None if cells is None else Path(cells))
    ctx._eval.update(shared_eval)  # decode the test videos once
    t0 = time.perf_counter()
    base = ctx.cell(f"syn_{n_seeds}_hog_r{ratio:g}", detector, _synthetic_build(ctx, n_seeds, ratio, fit))
    extd = ctx.cell(f"syn_{n_seeds}_hog_r{ratio:g}_ext_{tag}", detector,
                    _synthetic_build(ctx, n_seeds, ratio, ext_fit))
    shared_eval.update(ctx._eval)
    return {
        "base": base["test"]["ap"], "extended": extd["test"]["ap"],
        "base_iou03": base["test"]["ap_iou03"], "extended_iou03": extd["test"]["ap_iou03"],
        "gain": extd["test"]["ap"] - base["test"]["ap"],
        "seconds_this_run": round(time.perf_counter() - t0, 1),  # ~0 when both cells were cached
        "cell_seconds": {arm: {"build": c["train"].get("build_s"), "train": c["train"].get("train_s"),
                               "test": round(c["test"]["n_frames"] / max(c["test"]["frames_per_second"], 1e-9), 1)}
                         for arm, c in (("base", base), ("extended", extd))},
    }


def _significance(flag: bool | None) -> str:
    return "not tested by the diagnosis" if flag is None else ("significant" if flag else "NOT significant")


def _markdown(nb: dict[str, Any]) -> str:
    e = nb["extension"]
    lines = [f"## {nb['class']}: test AP (IoU 0.5), {nb['detector'].upper()} on real + synthetic "
             f"(r = {nb['ratio']:g}), base fit vs + {e['effect']} {e['setting']}", "",
             f"Extension source: {e['source']} ({_significance(e['significant'])}); "
             f"every {nb['stride_k']}th test frame.", "",
             "| training seed | base | extended | gain | base (IoU 0.3) | extended (IoU 0.3) |",
             "|---|---|---|---|---|---|"]
    for s, v in nb["per_seed"].items():
        lines.append(f"| {s} | {v['base']:.3f} | {v['extended']:.3f} | {v['gain']:+.3f} | {v['base_iou03']:.3f} | "
                     f"{v['extended_iou03']:.3f} |")
    m = nb["mean"]
    lines.append(f"| mean | {m['base']:.3f} | {m['extended']:.3f} | {m['gain']:+.3f} | {m['base_iou03']:.3f} | "
                 f"{m['extended_iou03']:.3f} |")
    return "\n".join(lines) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``python -m synthaug.diagnose.gain``."""
    p = argparse.ArgumentParser(prog="python -m synthaug.diagnose.gain", description=__doc__.split("\n\n")[0])
    p.add_argument("--class", dest="class_name", required=True, help="drone or airplane")
    p.add_argument("--report", default=None, help="diagnosis report.json (required without --extended-fit)")
    add_option(p, "--params", aliases=["--fit"], required=True,
               help="the base capture-parameter file (fit) the diagnosis ran on")
    p.add_argument("--out", required=True, help="output folder (extended_fit.json, gain.json, gain.md, cells)")
    add_option(p, "--seed-counts", aliases=["--n-seeds"], type=int, default=100, help="real seeds per training set")
    p.add_argument("--training-seeds", type=int, nargs="+", default=[0, 1, 2])
    p.add_argument("--ratio", type=float, default=None, help="synthetic per real (default: chosen on validation)")
    p.add_argument("--use-top-screened", action="store_true",
                   help="without a significant finding, extend with the top-screened candidate")
    p.add_argument("--effect", default=None, help="extend with this screened candidate (default: the first finding)")
    p.add_argument("--cells", default=None, help="cell cache (default <out>/cells.json)")
    add_option(p, "--seed-sets", aliases=["--seedsets"], default="data/halmstad/seedsets",
               help="folder of <class>_<n> seed sets")
    p.add_argument("--mesh", default=None)
    add_option(p, "--frame-stride", aliases=["--stride-k"], type=int, default=15, help="score every k-th test frame")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--extended-fit", default=None,
                   help="compare --params with this fitted file (a refit with an extension) instead of extending --params "
                        "by a diagnosis finding; --report is then not needed")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.report is None and args.extended_fit is None:
        print("gain: --report is required without --extended-fit", file=sys.stderr)
        return 2
    if args.threads < 1:
        print(f"gain: --threads must be >= 1, got {args.threads}", file=sys.stderr)
        return 2
    torch.set_num_threads(args.threads)

    def log(msg: str) -> None:
        print(f"[{time.strftime('%H:%M:%S')}] {msg}", flush=True)

    try:
        nb = run_gain(args.class_name, args.report, args.params, args.out, n_seeds=args.seed_counts,
                      training_seeds=args.training_seeds, ratio=args.ratio, use_top_screened=args.use_top_screened,
                      effect=args.effect, cells=args.cells, seedsets=args.seed_sets, mesh=args.mesh,
                      stride_k=args.frame_stride, log=log, extended_fit=args.extended_fit)
    except (ValueError, FileNotFoundError) as e:
        print(f"gain: error: {e}", file=sys.stderr)
        return 2
    print(json.dumps({"mean": nb["mean"], "gain_sd": nb["gain_sd"], "seconds": nb["seconds_this_run"]}))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
