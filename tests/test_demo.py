"""The README's main job (`synthaug demo`) end to end, at a tiny size, and the README's Python on its outputs."""

import json
import os
import re
from pathlib import Path

import pytest

from synthaug.cli import main

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """A tiny `synthaug demo --out outputs/demo` inside a scratch working directory (as the README runs it)."""
    import contextlib
    import io

    root = tmp_path_factory.mktemp("fresh_checkout")
    out = root / "outputs" / "demo"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["demo", "--out", str(out), "--videos", "3", "--frames", "30", "--seeds", "25", "--budget", "60",
                   "--ratio", "3", "--stride", "5", "--diagnosis-seeds", "10"])
    assert rc == 0
    return {"root": root, "out": out, "summary": json.loads(buf.getvalue().strip().splitlines()[-1])}


@pytest.mark.slow
def test_demo_runs_end_to_end(demo):
    out, summary = demo["out"], demo["summary"]
    aps = [v for k, v in summary.items() if k.startswith("real")]
    assert len(aps) == 2 and all(0.0 <= ap <= 1.0 for ap in aps)
    for name in ("README.md", "preview.png", "fitted_pairs.png", "joint_histograms.png", "pr_real.png",
                 "pr_ours.png", "fit_hog.json"):
        assert (out / name).exists(), name
    report = (out / "README.md").read_text()
    n_seeds = len(json.loads((out / "fit_hog.json").read_text())["rows"])  # the tiny videos give fewer than 25
    assert 10 <= n_seeds <= 25 and f"| real seeds only | {n_seeds} |" in report
    # the comparison is paired over 3 training seeds with a video-bootstrap interval, and said in words (issue 16)
    d = summary["difference"]
    assert d["low"] <= d["estimate"] <= d["high"] and d["estimate"] == pytest.approx(aps[1] - aps[0], abs=2e-4)
    assert summary["verdict"] in report and "Δ AP@0.5 vs real seeds only" in report
    word = "raised" if d["low"] > 0 else "LOWERED" if d["high"] < 0 else "No significant change"
    assert word in summary["verdict"]
    # and its interval with the training seeds resampled too (training randomness counted), said beside it
    c = summary["difference_seeds_resampled"]
    assert c["estimate"] == pytest.approx(d["estimate"]) and c["low"] <= c["high"]
    assert f"[{c['low']:+.3f}, {c['high']:+.3f}], coarse with 3 seeds" in summary["verdict"]
    # beside it, twice the real seeds (does this detector gain from more positives here at all?), paired the same way
    r = summary["reference_difference"]
    assert r["low"] <= r["estimate"] <= r["high"] and "Twice the real seeds" in summary["verdict"]
    assert r["estimate"] == pytest.approx(summary["2x real seeds (reference)"] - aps[0], abs=2e-4)
    assert "| 2x real seeds (reference) |" in report
    # the closing diagnosis (issue 6): a report on measured data with an effect hidden
    assert summary["diagnosis"]["hidden"] == "rotor_blur"
    assert "## Diagnosis" in report and (out / "diagnosis" / "report.md").exists()
    assert (out / "diagnosis_clean" / "report.md").exists()
    diag = json.loads((out / "diagnosis" / "report.json").read_text())
    # the demo's measured data are gray: the 14 candidates less the two colour-only ones (issue 20)
    assert diag["inputs"]["n_seeds"] == 10 and len(diag["screened"]) == 12
    assert sorted(diag["colour"]["not_offered"]) == ["chromatic_aberration", "white_balance"]
    assert not {"chromatic_aberration", "white_balance"} & {r["effect"] for r in diag["screened"]}


def readme_python_blocks():
    text = (REPO / "README.md").read_text()
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_readme_has_python_blocks():
    assert len(readme_python_blocks()) >= 2


@pytest.mark.slow
def test_readme_python_runs_verbatim_on_the_main_jobs_outputs(demo, monkeypatch):
    """Every ```python block of README.md, in order, in one namespace, from the folder the README's
    main job ran in (``outputs/demo`` relative paths)."""
    monkeypatch.chdir(demo["root"])
    namespace: dict = {"__name__": "__readme__"}
    for k, block in enumerate(readme_python_blocks()):
        code = compile(block, f"README.md python block {k + 1}", "exec")
        exec(code, namespace)  # noqa: S102 - the README's own code is the subject of the test
    # the first block's loop ran over real + synthetic batches: they collated together
    n = len(namespace["seeds"])
    assert namespace["ds"].n_real == n and namespace["ds"].n_synthetic == 20 * n
    images, targets = namespace["images"], namespace["targets"]
    assert os.path.exists("outputs/demo/fit_hog.json")
    assert len(images) == 8 and "boxes" in targets[0]
