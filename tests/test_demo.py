"""The README's main job (`synthaug demo`) end to end, at a tiny size."""

import json

import pytest

from synthaug.cli import main


@pytest.mark.slow
def test_demo_runs_end_to_end(tmp_path, capsys):
    out = tmp_path / "demo"
    rc = main(["demo", "--out", str(out), "--videos", "3", "--frames", "30", "--seeds", "6", "--budget", "60",
               "--ratio", "3", "--stride", "5", "--diagnosis-seeds", "10"])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    aps = [v for k, v in summary.items() if k.startswith("real")]
    assert len(aps) == 2 and all(0.0 <= ap <= 1.0 for ap in aps)
    for name in ("README.md", "preview.png", "fitted_pairs.png", "joint_histograms.png", "pr_real.png",
                 "pr_ours.png", "fit_hog.json"):
        assert (out / name).exists(), name
    report = (out / "README.md").read_text()
    assert "| real seeds only | 6 |" in report
    # the closing diagnosis (issue 6): a report on measured data with an effect hidden
    assert summary["diagnosis"]["hidden"] == "rotor_blur"
    assert "## Diagnosis" in report and (out / "diagnosis" / "report.md").exists()
    assert (out / "diagnosis_clean" / "report.md").exists()
    diag = json.loads((out / "diagnosis" / "report.json").read_text())
    assert diag["inputs"]["n_seeds"] == 10 and len(diag["screened"]) == 14
