import json
import math

import pytest
import torch

from synthaug.params import POSE_NAMES, CaptureParams


def test_paper_vector_order_and_shapes():
    names = CaptureParams.vector_names()
    assert names == ["alpha", "beta", "gamma", "t_x", "t_y", "sigma_s", "sigma_u", "sigma_v", "alpha_m", "sigma_n", "w_d"]
    t = CaptureParams.default(3)
    assert t.alpha.shape == (3,) and t.sigma_s.shape == (3, 1)
    assert CaptureParams.vector_names(channels=3)[5:8] == ["sigma_s[0]", "sigma_s[1]", "sigma_s[2]"]


@pytest.mark.parametrize("channels", [1, 3])
def test_vector_round_trip(channels):
    g = torch.Generator().manual_seed(0)
    t = CaptureParams.sample(5, generator=g, channels=channels)
    v = t.to_vector()
    assert v.shape == (5, 5 + 6 * channels)
    back = CaptureParams.from_vector(v, channels=channels)
    for n in t.names:
        torch.testing.assert_close(back.as_dict()[n], t.as_dict()[n], rtol=0, atol=0)


def test_from_vector_keeps_gradient():
    v = CaptureParams.default(2).to_vector().requires_grad_(True)
    t = CaptureParams.from_vector(v)
    (t.sigma_s.sum() * 2 + t.alpha.sum()).backward()
    assert v.grad[:, 5].tolist() == [2.0, 2.0] and v.grad[:, 0].tolist() == [1.0, 1.0]


def test_sampling_is_reproducible_and_in_range():
    a = CaptureParams.sample(100, generator=torch.Generator().manual_seed(3))
    b = CaptureParams.sample(100, generator=torch.Generator().manual_seed(3))
    assert torch.equal(a.to_vector(), b.to_vector())
    lo, hi = CaptureParams.bounds()
    v = a.to_vector()
    assert bool(((v >= lo) & (v <= hi)).all())


@pytest.mark.parametrize("field,value,match", [
    ("sigma_s", float("nan"), "sigma_s .* must be finite, got nan"),
    ("sigma_u", -0.5, "sigma_u .* must be >= 0, got -0.5"),
    ("w_d", 1.7, r"w_d .* must be in \[0.0, 1.0\] reflectance, got 1.7"),
    ("t_x", 0.9, r"t_x .* must be in \[-0.5, 0.5\]"),
    ("alpha", float("inf"), "alpha .* must be finite"),
])
def test_bad_values_name_field_and_value(field, value, match):
    with pytest.raises(ValueError, match=match):
        CaptureParams({field: [0.0 if field != "w_d" else 0.5, value]})


def test_periodic_angles_accept_any_finite_value_and_wrap():
    t = CaptureParams({"gamma": [7.0], "alpha_m": [2.0]})
    w = t.wrapped()
    assert math.isclose(float(w.gamma), 7.0 - 2 * math.pi, abs_tol=1e-6)
    assert math.isclose(float(w.alpha_m), 2.0 - math.pi, abs_tol=1e-6)


def test_unknown_field_and_bad_shapes():
    with pytest.raises(ValueError, match="unknown parameter"):
        CaptureParams({"sigma_x": 1.0})
    with pytest.raises(ValueError, match=r"expected a \(B, 11\) vector"):
        CaptureParams.from_vector(torch.zeros(2, 10))
    with pytest.raises(ValueError, match="channels must be 1 or 3"):
        CaptureParams(channels=2)
    with pytest.raises(ValueError, match="unknown effect"):
        CaptureParams(effects=["no_such_effect"])


def test_file_round_trip_is_human_readable(tmp_path):
    t = CaptureParams.sample(3, generator=torch.Generator().manual_seed(1), channels=3)
    path = tmp_path / "theta.json"
    t.save(path, extra=[{"distance": 0.1 * i} for i in range(3)], metadata={"mesh": "quadcopter"})
    doc = json.loads(path.read_text())
    assert doc["format"] == "synthaug.capture_params" and doc["version"] == 1
    assert {f["name"]: f["unit"] for f in doc["fields"]}["sigma_s"] == "px"
    back, extra, meta = CaptureParams.load_with_extra(path)
    assert torch.allclose(back.to_vector(), t.to_vector())
    assert extra[2]["distance"] == pytest.approx(0.2) and meta == {"mesh": "quadcopter"}


def test_load_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        CaptureParams.load(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ValueError, match="not a JSON"):
        CaptureParams.load(bad)
    t = CaptureParams.default(1)
    t.save(bad)
    doc = json.loads(bad.read_text())
    doc["rows"][0]["theta"]["sigma_n"] = [float("nan")]
    bad.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="sigma_n .* must be finite"):
        CaptureParams.load(bad)


def test_indexing_and_cat():
    t = CaptureParams.sample(4, generator=torch.Generator().manual_seed(0))
    sub = t[[3, 1]]
    assert torch.equal(sub.to_vector(), t.to_vector()[[3, 1]])
    assert CaptureParams.cat([t[0], t[1]]).batch_size == 2
    assert set(POSE_NAMES) <= set(t.names)
