"""`synthaug preview` and `synthaug bench render` end to end (small settings)."""

import json

import numpy as np
import pytest
from PIL import Image

from synthaug.cli import main


def test_preview_writes_a_grid(tmp_path, capsys):
    out = tmp_path / "p.png"
    assert main(["preview", "--out", str(out), "--n", "8", "--zoom", "2", "--step-deg", "30"]) == 0
    info = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert info["samples"] == 8
    img = np.asarray(Image.open(out))
    # a 14-px header row of column names, then 8 tiles of 40x40 at zoom 2 in one row of 8 columns
    assert img.shape == (14 + 2 + 80 + 2, 8 * 82 + 2)
    assert (img[:14] < 128).any()  # the header has text


def test_preview_real_beside_synthetic(tmp_path, capsys):
    from synthaug.data.seedset import write_seedset
    from synthaug.data.procedural import sky_backgrounds

    bgs = sky_backgrounds(3, (40, 40), seed=0)
    patches = bgs.copy()
    patches[:, 15:25, 10:30] = 30
    frames = sky_backgrounds(3, (64, 64), seed=1)
    write_seedset(tmp_path / "seeds", patches=patches, backgrounds=bgs, boxes=[[0, 0, 10, 10]] * 3,
                  centres=[[5, 5]] * 3, crops=[[5, 5, 14]] * 3, records=[{"video": "v"}] * 3,
                  frames=list(frames), background_frames=list(frames),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    out = tmp_path / "rs.png"
    assert main(["preview", "--out", str(out), "--seeds", str(tmp_path / "seeds"), "--per-seed", "2",
                 "--zoom", "1", "--step-deg", "30"]) == 0
    img = np.asarray(Image.open(out))
    top, left = 14, 6 * len("seed 0") + 6  # column headers above, row labels on the left
    assert img.shape == (top + 3 * 42 + 2, left + 4 * 42 + 2)
    assert (img[:top, left:] < 128).any() and (img[top:, :left] < 128).any()
    # first column is the real patch, untouched
    np.testing.assert_array_equal(img[top + 2:top + 42, left + 2:left + 42], patches[0])


def test_bench_render_prints_json(capsys):
    assert main(["bench", "render", "--mode", "patch", "--workers", "0", "--batches", "2", "--repeats", "1",
                 "--batch-size", "16", "--step-deg", "30"]) == 0
    doc = json.loads(capsys.readouterr().out)
    r = doc["results"][0]
    assert r["mode"] == "patch" and r["samples_per_s_median"] > 0 and r["peak_rss_main_mib"] > 0


def test_unknown_subcommand_exits_nonzero():
    with pytest.raises(SystemExit) as exc:
        main(["frobnicate"])
    assert exc.value.code == 2  # argparse's usage error (a bare raises(SystemExit) also passed on exit 0)
