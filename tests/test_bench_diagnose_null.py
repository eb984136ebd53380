"""The null/power benchmark's bookkeeping (benchmarks/bench_diagnose_null.py): what counts as naming an effect."""

from __future__ import annotations

import pytest


def test_a_candidate_is_named_by_the_first_finding(bench_null):
    assert bench_null._first_name(["gamma (noise_level)", "defocus (distance:pixel)"], "gamma") == "gamma"
    assert bench_null._first_name(["haze (distance:feature)"], "gamma") == "haze"
    assert bench_null._first_name([], "gamma") is None


def test_an_outside_effect_is_named_by_its_structure_in_an_unexplained_finding(bench_null):
    from synthaug.diagnose.reference_camera import OUTSIDE_EFFECTS

    assert set(bench_null.OUTSIDE_STRUCTURE) == set(OUTSIDE_EFFECTS)  # every outside effect has its structure
    f = bench_null._first_name
    assert f(["unexplained: column_pattern"], "column_pattern") == "column_pattern"
    # a blur candidate may explain part of interlacing's comb: the comb reported as unexplained still names it
    assert f(["defocus (distance:pixel)", "unexplained: high_frequency, periodic_rows"], "interlacing") == "interlacing"
    # the wrong structure, or a candidate alone, is a misnaming
    assert f(["unexplained: tone_curve"], "column_pattern") == "unexplained"
    assert f(["defocus (distance:pixel)"], "interlacing") == "defocus"


def test_wilson_interval_matches_the_formula_by_hand(bench_null):
    # Wilson score interval by hand: (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)
    import math

    k, n, z = 3, 20, 1.959963984540054
    p = k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    assert bench_null.wilson(k, n) == pytest.approx((c - h, c + h), abs=1e-9)


def test_floors_pooled_from_outputs_name_a_frame_refresh(bench_null, tmp_path):
    """``--floors-from`` pools the outputs' null values per statistic (the floors are ``derive_floors``' of the
    pooled values, the rule by hand for one) and its source names an output whose frame statistics were remade
    without a refit (``frame_recalibrate.py``'s ``frame_refresh``) or whose periodic measures were
    (``periodic_s96/recalibrate.py``'s ``structure_refresh``), and says nothing of one that was not."""
    import argparse
    import importlib.util as iu
    import json

    import numpy as np

    from synthaug.diagnose.calibration import derive_floors

    rng = np.random.default_rng(4)
    outs = []
    for name, n, refresh in (("a.json", 12, None), ("b.json", 10, {"by": "python frame_recalibrate.py X"}),
                             ("c.json", 9, "structure")):
        gains = [round(float(v), 6) for v in np.abs(rng.normal(0.005, 0.004, n))]
        d = {"command": f"python bench {name}", "fit": "converged", "cases": n, "seeds": 60,
             "null_distributions": {"screen:lens_distortion:frame": {"gain": {"values": gains}},
                                    "screen:gamma:noise_level": {"slope": {"values": gains}}}}
        if refresh == "structure":
            d["structure_refresh"] = {"by": "python recalibrate.py Y", "statistics": ["residual:periodic_rows"]}
        elif refresh:
            d["frame_refresh"] = refresh
        (tmp_path / name).write_text(json.dumps(d))
        outs.append(gains)
    dest = tmp_path / "nf.py"
    bench_null.pool_floors(argparse.Namespace(floors_from=[str(tmp_path / f) for f in ("a.json", "b.json", "c.json")],
                                              write_floors=str(dest)))
    spec = iu.spec_from_file_location("nf_pooled", dest)
    mod = iu.module_from_spec(spec)
    spec.loader.exec_module(mod)
    pooled = np.array(outs[0] + outs[1] + outs[2])
    f = derive_floors([{"screen:lens_distortion:frame": {"gain": v}} for v in pooled]
                      + [{"screen:gamma:noise_level": {"slope": v}} for v in pooled])
    assert mod.SCREEN["lens_distortion:frame"] == pytest.approx(f["SCREEN"]["lens_distortion:frame"], abs=1e-6)
    z1 = float(mod.SOURCE["z_one_sided"])
    by_hand = max(max(pooled.mean(), 0.0) + z1 * pooled.std(ddof=1), pooled.max())
    assert mod.SCREEN["lens_distortion:frame"] == pytest.approx(by_hand, abs=1e-4)
    assert mod.SOURCE["n_cases"] == 31
    src = mod.SOURCE["command"]
    assert "python bench a.json [converged fit, 12 cases]" in src
    assert "python bench b.json [converged fit, 10 cases; frame statistics remade by python frame_recalibrate.py X]" \
        in src
    assert "python bench c.json [converged fit, 9 cases; residual:periodic_rows remade by python recalibrate.py Y]" \
        in src


def test_colour_floors_pooled_from_a_clean_colour_output(bench_null, tmp_path):
    """``--colour-floors-from``: the colour channels' floors from a clean colour run, named in the source; an
    output that is not a clean colour run is refused."""
    import argparse
    import importlib.util as iu
    import json

    gray = {"command": "python bench gray", "fit": "converged", "cases": 12, "seeds": 60,
            "null_distributions": {"screen:gamma:distance:pixel": {"gain": {"values": [0.001 * k for k in range(12)]}}}}
    colour = {"command": "python bench --colour", "fit": "converged", "cases": 11, "seeds": 60, "colour": True,
              "hidden": None, "null_distributions": {
                  "screen:haze:distance:colour": {"gain": {"values": [-0.02 + 0.002 * k for k in range(11)]}}}}
    for name, d in (("g.json", gray), ("c.json", colour), ("h.json", {**colour, "hidden": "haze"})):
        (tmp_path / name).write_text(json.dumps(d))
    dest = tmp_path / "nf.py"
    ns = dict(floors_from=[str(tmp_path / "g.json")], write_floors=str(dest))
    bench_null.pool_floors(argparse.Namespace(**ns, colour_floors_from=[str(tmp_path / "c.json")]))
    spec = iu.spec_from_file_location("nf_colour_pooled", dest)
    mod = iu.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert "haze:distance:colour" in mod.SCREEN and "gamma:distance:pixel" in mod.SCREEN
    assert mod.SOURCE["colour"]["n_cases"] == 11 and "python bench --colour" in mod.SOURCE["colour"]["command"]
    with pytest.raises(SystemExit, match="not a clean colour run"):
        bench_null.pool_floors(argparse.Namespace(**ns, colour_floors_from=[str(tmp_path / "h.json")]))


def test_a_case_records_the_gains_another_candidate_explained_better(bench_null):
    from synthaug.diagnose.screening import explained_better

    ch = [[{"channel": "distance:pixel", "gain": 0.049, "significant": True, "other_ok": True}],
          [{"channel": "distance:pixel", "gain": 0.065, "significant": False, "other_ok": True}],
          [{"channel": "distance:feature", "gain": 0.03, "significant": True, "other_ok": True}]]
    explained_better(["defocus", "haze", "gamma"], ch)  # the screening's own rule marks the channels
    report = {"screened": [{"effect": e, "channels": c} for e, c in zip(["defocus", "haze", "gamma"], ch)]}
    assert bench_null.explained_better(report) == ["defocus (distance:pixel) < haze"]
    assert bench_null.explained_better({"screened": []}) == []


def test_an_outputs_absorbed_gains_come_back_with_their_sign(bench_null, tmp_path):
    import json

    out = {"null_distributions": {
        "screen:exposure:absorbed": {"gain": {"values": [0.1, 0.243]}, "rho": {"values": [-0.3, 0.5]}},
        "screen:gamma:distance:pixel": {"gain": {"values": [0.01, 0.02]}, "rho": {"values": [9.0, 9.0]}}}}
    (tmp_path / "a.json").write_text(json.dumps(out))
    rows, _ = bench_null.stats_from_output(tmp_path / "a.json")
    ab, px = "screen:exposure:absorbed", "screen:gamma:distance:pixel"
    assert rows == [{ab: {"gain": 0.1, "rho": -0.3}, px: {"gain": 0.01}},
                    {ab: {"gain": 0.243, "rho": 0.5}, px: {"gain": 0.02}}]
    out["null_distributions"]["screen:exposure:absorbed"]["rho"]["values"] = [-0.3]
    (tmp_path / "b.json").write_text(json.dumps(out))
    with pytest.raises(ValueError, match="do not pair up"):
        bench_null.stats_from_output(tmp_path / "b.json")


def test_the_floors_count_each_absorbed_dependence_in_its_effects_direction(bench_null):
    from synthaug.diagnose.screening import ABSORPTION

    d = bench_null.absorbed_directions()
    assert d["exposure:absorbed"] == -1 and d["sharpening:absorbed"] == +1  # auto-exposure darkens w_d; sharpening
    assert set(d) == {f"{e}:absorbed" for e in ABSORPTION}
