"""The null/power benchmark's bookkeeping (benchmarks/bench_diagnose_null.py): what counts as naming an effect."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_diagnose_null.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_diagnose_null", _PATH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_a_candidate_is_named_by_the_first_finding(bench):
    assert bench._first_name(["gamma (noise_level)", "defocus (distance:pixel)"], "gamma") == "gamma"
    assert bench._first_name(["haze (distance:feature)"], "gamma") == "haze"
    assert bench._first_name([], "gamma") is None


def test_an_outside_effect_is_named_by_its_structure_in_an_unexplained_finding(bench):
    from synthaug.diagnose.reference_camera import OUTSIDE_EFFECTS

    assert set(bench.OUTSIDE_STRUCTURE) == set(OUTSIDE_EFFECTS)  # every outside effect has its structure
    f = bench._first_name
    assert f(["unexplained: column_pattern"], "column_pattern") == "column_pattern"
    # a blur candidate may explain part of interlacing's comb: the comb reported as unexplained still names it
    assert f(["defocus (distance:pixel)", "unexplained: high_frequency, periodic_rows"], "interlacing") == "interlacing"
    # the wrong structure, or a candidate alone, is a misnaming
    assert f(["unexplained: tone_curve"], "column_pattern") == "unexplained"
    assert f(["defocus (distance:pixel)"], "interlacing") == "defocus"


def test_wilson_interval_matches_the_formula_by_hand(bench):
    # Wilson score interval by hand: (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)
    import math

    k, n, z = 3, 20, 1.959963984540054
    p = k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    assert bench.wilson(k, n) == pytest.approx((c - h, c + h), abs=1e-9)
