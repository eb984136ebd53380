"""Reporting helpers of the experiments: a markdown table, its numbers as JSON, and a plot per experiment.

Each experiment writes ``<name>.md`` (:func:`_write_report`), ``<name>.json``
and ``<name>.png`` (:func:`_plot`) into the context's output folder; with a base
seed other than 0 the stem is ``<name>_seed<k>`` (:func:`_stem`).

Example:
    >>> _fmt(0.12345), _fmt(None), _fmt(3)
    ('0.123', '–', '3')
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Mapping, Sequence

import numpy as np

from synthaug._io import atomic_write_text

if TYPE_CHECKING:
    from synthaug.evaluate.context import ExperimentContext


def _fmt(x: Any) -> str:
    return "–" if x is None else f"{x:.3f}" if isinstance(x, float) else str(x)


def _stem(ctx: ExperimentContext, name: str) -> str:
    """Output file stem: ``name``, or ``name_seed<k>`` for a base seed other than 0."""
    return name if ctx.seed == 0 else f"{name}_seed{ctx.seed}"


def _write_report(ctx: ExperimentContext, name: str, title: str, header: Sequence[str], rows: Sequence[Sequence[Any]],
                  numbers: dict[str, Any], notes: str = "") -> None:
    ctx.out_dir.mkdir(parents=True, exist_ok=True)
    lines = [f"## {title}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_fmt(v) for v in r) + " |" for r in rows]
    if notes:
        lines += ["", notes]
    atomic_write_text(ctx.out_dir / f"{_stem(ctx, name)}.md", "\n".join(lines) + "\n")
    atomic_write_text(ctx.out_dir / f"{_stem(ctx, name)}.json", json.dumps(numbers, indent=1, default=str) + "\n")


def _plot(path: Path, kind: Literal["bar", "line"], series: Mapping[str, Mapping[Any, float | None]], *, title: str, xlabel: str,
          ylabel: str = "AP (IoU 0.5)", logx: bool = False, marks: Mapping[str, Any] | None = None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4), dpi=110)
    try:
        if kind == "line":
            for label, pts in series.items():
                xs = [x for x in pts if pts[x] is not None]  # missing cells: the line joins the measured points
                ys = [pts[x] for x in xs]
                xp = [x + 1 for x in xs] if logx else xs
                ax.plot(xp, ys, marker="o", label=label)
                if marks and label in marks and pts.get(marks[label]) is not None:
                    x = marks[label]
                    ax.plot([x + 1 if logx else x], [pts[x]], marker="*", markersize=14, color="k", linestyle="none")
            if logx:
                ax.set_xscale("log")
                ax.set_xlabel(xlabel + " (+1, log)")
            else:
                ax.set_xlabel(xlabel)
        else:
            groups = list(series.keys())
            cats = list(dict.fromkeys(c for g in series.values() for c in g))
            width = 0.8 / max(len(cats), 1)
            for j, c in enumerate(cats):
                ys = [np.nan if series[g].get(c) is None else series[g][c] for g in groups]
                ax.bar(np.arange(len(groups)) + (j - (len(cats) - 1) / 2) * width, ys, width, label=str(c))
            ax.set_xticks(np.arange(len(groups)), groups)
            ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_ylim(0, max(0.05, min(1.0, 1.15 * max([v for s in series.values() for v in s.values() if v is not None] or [0.05]))))
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path)
    finally:
        plt.close(fig)


def _ap(cell: dict[str, Any], split: str = "test", key: str = "ap") -> float | None:
    return cell.get(split, {}).get(key)
