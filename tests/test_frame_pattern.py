"""Patterns fixed in the frame (synthaug.diagnose.frame_pattern) against hand-made frames and known nulls."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from synthaug.diagnose.frame_pattern import fixed_line_pattern, line_profiles


def test_line_profiles_against_a_hand_computed_frame():
    f = np.full((30, 50), 100, np.uint8)
    f[:, 20] = 120  # one brighter column
    f[5:15, 30:40] = 250  # the object's square, left out
    p = line_profiles(f, exclude=(30, 5, 10), high_pass=5)
    m = np.log(np.full(50, 100 / 255.0))
    m[20] = np.log(120 / 255.0)
    box = np.convolve(np.pad(m, 2, mode="edge"), np.ones(5) / 5, mode="valid")  # a 5-px running mean, edges kept
    np.testing.assert_allclose(p["x"], m - box, atol=1e-12)
    # every row has the same mean once the object's square is left out: the row profile is flat
    assert np.abs(p["y"]).max() < 1e-3
    # colour: the mean of the channels
    np.testing.assert_allclose(line_profiles(np.dstack([f, f, f]), exclude=(30, 5, 10), high_pass=5)["x"], p["x"])
    with pytest.raises(ValueError, match="shape"):
        line_profiles(np.zeros((2, 3, 4, 5)))


def test_identical_profiles_agree_fully_and_opposite_ones_disagree():
    rng = np.random.default_rng(0)
    g = rng.standard_normal(64)
    out = fixed_line_pattern([g, g, g], ["a", "b", "c"], np.random.default_rng(1), n_perm=199)
    assert out["rho"] == pytest.approx(1.0)
    np.testing.assert_allclose(out["pattern"], g)
    assert out["amplitude"] == pytest.approx(g.std())
    # two videos, one the negative of the other: agreement -1
    assert fixed_line_pattern([g, -g], ["a", "b"], np.random.default_rng(1), n_perm=99)["rho"] == pytest.approx(-1.0)


def test_seeds_of_one_video_are_averaged_and_other_sizes_left_out():
    rng = np.random.default_rng(2)
    a, b = rng.standard_normal(40), rng.standard_normal(40)
    out = fixed_line_pattern([a, a + 0.0, b, rng.standard_normal(30)], ["v1", "v1", "v2", "v3"],
                             np.random.default_rng(0), n_perm=99)
    # v3's frames have another size: only v1 (mean a) and v2 (b) are compared, by hand
    expect = float(a @ b / (0.5 * (a @ a + b @ b)))
    assert out["groups"] == 2 and out["seeds"] == 3 and out["length"] == 40
    assert out["rho"] == pytest.approx(expect)
    # fewer than two videos: nothing to compare
    assert fixed_line_pattern([a, b], ["v1", "v1"], np.random.default_rng(0)) is None
    assert fixed_line_pattern([], [], np.random.default_rng(0)) is None


def test_null_p_values_are_uniform():
    # videos whose profiles share nothing: the permutation p-value is uniform (a calibrated test)
    rng = np.random.default_rng(3)
    ps = []
    for _ in range(300):
        prof = [rng.standard_normal(96) for _ in range(8)]
        ps.append(fixed_line_pattern(prof, [i % 4 for i in range(8)], rng, n_perm=199)["p"])
    ps = np.array(ps)
    assert stats.kstest(ps, "uniform").pvalue > 0.01
    assert 0.03 <= float(np.mean(ps < 0.1)) <= 0.17  # binomial(300, 0.1): 0.1 +- 4 sd


def test_a_shared_pattern_is_found_among_strong_scene_structure():
    # each video's own scene structure (twice the pattern's amplitude, fixed within the video) hides a 1 % gain
    # pattern in any one frame; the agreement across videos finds it, and its estimate follows the truth
    rng = np.random.default_rng(4)
    gain = 0.01 * rng.standard_normal(256)
    scenes = [0.02 * rng.standard_normal(256) for _ in range(6)]
    prof = [scenes[i % 6] + gain + 0.002 * rng.standard_normal(256) for i in range(36)]
    out = fixed_line_pattern(prof, [i % 6 for i in range(36)], np.random.default_rng(5), n_perm=999)
    assert out["p"] < 0.01 and 0.05 < out["rho"] < 0.5  # about 1 / (1 + 2^2)
    assert np.corrcoef(out["pattern"], gain)[0, 1] > 0.4
    # without the pattern: no finding
    prof0 = [scenes[i % 6] + 0.002 * rng.standard_normal(256) for i in range(36)]
    assert fixed_line_pattern(prof0, [i % 6 for i in range(36)], np.random.default_rng(5), n_perm=999)["p"] > 0.01


def test_a_periodic_pattern_gets_its_period():
    rng = np.random.default_rng(6)
    x = np.arange(256)
    gain = 0.01 * (x % 8 == 0)  # a jump every 8 columns (a block grid)
    prof = [gain - gain.mean() + 0.003 * rng.standard_normal(256) for _ in range(10)]
    out = fixed_line_pattern(prof, list(range(10)), np.random.default_rng(0), n_perm=199)
    assert out["period_px"] == pytest.approx(8.0) and out["peak_ratio"] > 20
    white = fixed_line_pattern([0.01 * rng.standard_normal(256)] * 4, list(range(4)), np.random.default_rng(0),
                               n_perm=99)
    assert white["peak_ratio"] < 20
