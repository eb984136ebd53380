"""Null calibration of the diagnosis (issue 20, item 3): floors from clean data, one rule everywhere."""

from __future__ import annotations

import importlib.util
import sys
import types

import numpy as np
import pytest
from scipy import stats

from synthaug.diagnose import calibration
from synthaug.diagnose.calibration import HAND_FLOORS, derive_floors, structure_significant


def _fake_floors(monkeypatch, structure, screen):
    mod = types.ModuleType("synthaug.diagnose.null_floors")
    mod.SOURCE = {"command": "test", "date": "2026-01-01", "n_cases": 20, "n_seeds": 60, "family_rate": 0.05,
                  "z_two_sided": 3.0, "z_one_sided": 2.8, "n_statistics": 3}
    mod.STRUCTURE, mod.SCREEN = structure, screen
    monkeypatch.setitem(sys.modules, "synthaug.diagnose.null_floors", mod)
    import synthaug.diagnose as pkg

    monkeypatch.setattr(pkg, "null_floors", mod, raising=False)
    return mod


def test_derive_floors_by_hand():
    rng = np.random.default_rng(0)
    tone = rng.normal(-0.2, 0.05, 30)
    gain = rng.normal(-0.004, 0.002, 30)
    rows = [{"residual:tone_curve": {"value": float(t)}, "screen:gamma:distance:pixel": {"gain": float(g)},
             "screen:gamma:distance:colour": {"gain": 1.0}} for t, g in zip(tone, gain)]
    rows[0]["residual:radial"] = {"value": 0.3}  # seen once: not calibrated
    f = derive_floors(rows)
    assert f["n_statistics"] == 2 and "radial" not in f["STRUCTURE"]  # colour is never calibrated (gray nulls)
    assert set(f["SCREEN"]) == {"gamma:distance:pixel"}
    z2, z1 = stats.norm.isf(0.05 / 4), stats.norm.isf(0.05 / 2)
    assert f["z_two_sided"] == pytest.approx(z2) and f["z_one_sided"] == pytest.approx(z1)
    lo, hi = f["STRUCTURE"]["tone_curve"]
    sd = tone.std(ddof=1)
    # the null family: the clean mean (-0.2) and an exactly right model (0), each +- z sd
    assert lo == pytest.approx(min(tone.mean() - z2 * sd, tone.min()))
    assert hi == pytest.approx(max(0.0 + z2 * sd, tone.max()))
    assert lo < -0.2 and 0 < hi < 0.2
    assert f["SCREEN"]["gamma:distance:pixel"] == pytest.approx(max(0.0 + z1 * gain.std(ddof=1), gain.max()))
    # the clean mean of each candidate statistic: the "no effect" value of one without a physical zero
    assert f["CENTRE"] == {"gamma:distance:pixel": pytest.approx(gain.mean())}
    # where the clean values stay, not clamped at 0 as the floor is (the mean here is negative)
    assert f["UPPER"] == {"gamma:distance:pixel": pytest.approx(max(gain.mean() + z1 * gain.std(ddof=1), gain.max()))}
    assert f["UPPER"]["gamma:distance:pixel"] < f["SCREEN"]["gamma:distance:pixel"]


def test_an_absorbed_dependence_of_the_wrong_sign_sets_no_floor():
    """The absorbed channel names its effect only for the sign the effect predicts (auto-exposure: w_d falls with
    the frame's brightness, sign -1), so a clean case whose w_d rises with it is no gain: counted as -|R²|."""
    from synthaug.diagnose.screening import ABSORPTION

    assert ABSORPTION["exposure"][2] == -1
    rng = np.random.default_rng(1)
    r2 = rng.normal(-0.01, 0.04, 30)
    rho = rng.choice([-0.3, 0.3], 30)
    r2[7], rho[7] = 0.5, +0.7  # the largest clean R² has the wrong sign
    rows = [{"screen:exposure:absorbed": {"gain": float(g), "rho": float(r)}} for g, r in zip(r2, rho)]
    f = derive_floors(rows, directions={"exposure:absorbed": ABSORPTION["exposure"][2]})
    signed = np.where(rho < 0, r2, -np.abs(r2))  # by hand
    z1 = stats.norm.isf(0.05 / 1)
    assert f["SCREEN"]["exposure:absorbed"] == pytest.approx(
        max(max(signed.mean(), 0.0) + z1 * signed.std(ddof=1), signed.max()))
    assert f["SCREEN"]["exposure:absorbed"] < 0.5 and f["CENTRE"]["exposure:absorbed"] == pytest.approx(signed.mean())
    # without the sign (an older output) or without the directions, the value counts as it is
    f0 = derive_floors([{"screen:exposure:absorbed": {"gain": float(g)}} for g in r2],
                       directions={"exposure:absorbed": -1})
    assert f0["SCREEN"]["exposure:absorbed"] == pytest.approx(0.5)
    assert derive_floors(rows)["SCREEN"]["exposure:absorbed"] == pytest.approx(0.5)


def test_floors_hold_the_family_false_alarm_rate_on_fresh_null_cases():
    """Monte Carlo: 12 statistics with shifted normal nulls, floors from 30 clean cases, then fresh clean cases:
    the share with any statistic outside its floor is about the 5 % the rule is set for (<= 10 % here, as 30
    cases estimate sigma with ~13 % error)."""
    rng = np.random.default_rng(1)
    mu, sd = rng.normal(0, 1, 12), rng.uniform(0.5, 2.0, 12)

    def case():
        v = rng.normal(mu, sd)
        return {f"residual:m{j}": {"value": float(v[j])} for j in range(6)} | \
            {f"screen:e{j}:distance:pixel": {"gain": float(v[j])} for j in range(6, 12)}

    rates = []
    for _ in range(40):
        f = derive_floors([case() for _ in range(30)])
        fresh = [case() for _ in range(50)]
        alarms = [any(not f["STRUCTURE"][f"m{j}"][0] <= c[f"residual:m{j}"]["value"] <= f["STRUCTURE"][f"m{j}"][1]
                      for j in range(6))
                  or any(c[f"screen:e{j}:distance:pixel"]["gain"] > f["SCREEN"][f"e{j}:distance:pixel"]
                         for j in range(6, 12)) for c in fresh]
        rates.append(np.mean(alarms))
    assert 0.005 < np.mean(rates) <= 0.10, np.mean(rates)


def test_structure_rule_uses_the_null_range_and_falls_back_to_hand_floors(monkeypatch):
    _fake_floors(monkeypatch, {"tone_curve": [-0.6, -0.1]}, {"gamma:distance:pixel": 0.01})
    # inside the clean range: not a finding however small p is
    assert structure_significant("tone_curve", -0.35, 1e-12, 0.001) == (False, [-0.6, -0.1])
    assert structure_significant("tone_curve", -0.7, 1e-12, 0.001)[0]
    assert structure_significant("tone_curve", 0.05, 1e-12, 0.001)[0]  # positive: outside a negative null
    assert not structure_significant("tone_curve", 0.05, 0.01, 0.001)[0]  # the test must reject too
    assert not structure_significant("tone_curve", float("nan"), 1e-12, 0.001)[0]
    # not calibrated: the hand-set floor on |value|
    assert structure_significant("radial", 0.6, 1e-9, 0.001) == (True, HAND_FLOORS["radial"])
    assert structure_significant("radial", 0.4, 1e-9, 0.001) == (False, HAND_FLOORS["radial"])
    assert calibration.gain_floor("gamma", "distance:pixel") == 0.01
    assert calibration.gain_floor("gamma", "absorbed") is None
    text = calibration.rule_text()
    assert "20 clean" in text and "test" in text and "hand-set" in text


def test_write_floors_module_round_trip(tmp_path, monkeypatch):
    rng = np.random.default_rng(2)
    rows = [{"residual:high_frequency": {"value": float(v)}, "screen:gamma:noise_level": {"slope": float(s)}}
            for v, s in zip(rng.normal(-0.3, 0.1, 12), rng.normal(0.0, 0.05, 12))]
    path = calibration.write_floors_module(tmp_path / "nf.py", rows, command="python bench --cases 12",
                                          n_cases=12, n_seeds=60)
    spec = importlib.util.spec_from_file_location("nf", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    f = derive_floors(rows)
    assert mod.SOURCE["command"] == "python bench --cases 12" and mod.SOURCE["n_cases"] == 12
    np.testing.assert_allclose(mod.STRUCTURE["high_frequency"], f["STRUCTURE"]["high_frequency"], atol=1e-6)
    # gamma's noise channel is the slope in gamma's direction (a compressive curve: falling, sign -1)
    from synthaug.diagnose.noise import NOISE_CANDIDATES

    slopes = np.array([r["screen:gamma:noise_level"]["slope"] for r in rows]) * NOISE_CANDIDATES["gamma"]
    z1 = stats.norm.isf(0.05 / 2)
    assert mod.SCREEN["gamma:noise_level"] == pytest.approx(max(max(slopes.mean(), 0) + z1 * slopes.std(ddof=1),
                                                                slopes.max()), abs=1e-6)
    assert mod.CENTRE["gamma:noise_level"] == pytest.approx(slopes.mean(), abs=1e-6)
    # read back by gain_centre; a calibration written before centres were kept has none
    with monkeypatch.context() as m:
        m.setattr(calibration, "_floors", lambda: mod)
        assert calibration.gain_centre("gamma", "noise_level") == pytest.approx(slopes.mean(), abs=1e-6)
        assert calibration.gain_centre("sharpening", "frame") is None
        upper = max(slopes.mean() + z1 * slopes.std(ddof=1), slopes.max())
        assert calibration.gain_upper("gamma", "noise_level") == pytest.approx(upper, abs=1e-6)
        del mod.CENTRE, mod.UPPER
        assert calibration.gain_centre("gamma", "noise_level") is None
        assert calibration.gain_upper("gamma", "noise_level") is None


def test_colour_floors_come_from_colour_cases_only_with_the_colour_cases_count(tmp_path, monkeypatch):
    """The colour channel's chroma gains are floored from clean colour cases (stop 93), with z for the statistics
    a colour case holds (the gray ones and the colour ones); a gray row's colour entry is never used, and the gray
    floors are the same as without colour cases."""
    rng = np.random.default_rng(3)
    gray = [{"residual:tone_curve": {"value": float(t)}, "screen:gamma:distance:pixel": {"gain": float(g)},
             "screen:haze:distance:colour": {"gain": 5.0}}
            for t, g in zip(rng.normal(-0.2, 0.05, 20), rng.normal(0.0, 0.01, 20))]
    wb, haze = rng.normal(-0.05, 0.04, 15), rng.normal(-0.01, 0.01, 15)
    colour = [{"screen:white_balance:distance:colour": {"gain": float(a)},
               "screen:haze:distance:colour": {"gain": float(b)},
               "screen:gamma:distance:pixel": {"gain": 9.0}}  # a colour case's gray statistic: not pooled
              for a, b in zip(wb, haze)]
    alone, f = derive_floors(gray), derive_floors(gray, colour_stats=colour)
    assert f["STRUCTURE"] == alone["STRUCTURE"] and f["z_one_sided"] == alone["z_one_sided"]
    assert f["SCREEN"]["gamma:distance:pixel"] == alone["SCREEN"]["gamma:distance:pixel"]
    z1c = stats.norm.isf(0.05 / 4)  # 2 gray statistics + 2 colour ones on a colour case
    assert f["colour"] == {"z_one_sided": pytest.approx(z1c), "n_statistics": 4}
    for name, v in (("white_balance", wb), ("haze", haze)):
        want = max(max(v.mean(), 0.0) + z1c * v.std(ddof=1), v.max(), 0.0)
        assert f["SCREEN"][f"{name}:distance:colour"] == pytest.approx(want)
        assert f["CENTRE"][f"{name}:distance:colour"] == pytest.approx(v.mean())
    path = calibration.write_floors_module(tmp_path / "nf.py", gray, command="gray", n_cases=20, n_seeds=60,
                                          colour_stats=colour, colour_source={"command": "colour", "n_cases": 15})
    spec = importlib.util.spec_from_file_location("nf_colour", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.SOURCE["colour"] == {"command": "colour", "n_cases": 15, "z_one_sided": round(z1c, 4),
                                    "n_statistics": 4}
    with monkeypatch.context() as m:
        m.setattr(calibration, "_floors", lambda: mod)
        assert calibration.gain_floor("haze", "distance:colour") == pytest.approx(f["SCREEN"]["haze:distance:colour"])
        text = calibration.rule_text()
        assert "15 clean colour cases" in text and "hand-set" not in text
