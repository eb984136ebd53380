"""The cell cache: keys from everything that changes a result, atomic files, one computation across processes."""

import json
import multiprocessing as mp
import time

import pytest

from synthaug.evaluate.cells import CellCache, canonical_json, cell_key


def test_key_covers_every_field_and_ignores_order():
    base = {"protocol": "abc123", "kind": "hog", "seed": 0, "scales": [1.25, 1.0], "options": {"ada_rounds": 100}}
    assert cell_key(base) == cell_key(dict(reversed(list(base.items()))))
    for field, other in [("protocol", "abc124"), ("seed", 1), ("scales", [1.25, 0.8]), ("options", {"ada_rounds": 101}),
                         ("kind", "cnn")]:
        assert cell_key({**base, field: other}) != cell_key(base), field
    assert cell_key({**base, "extra": None}) != cell_key(base)
    with pytest.raises(ValueError, match="plain JSON"):
        cell_key({"x": object()})
    with pytest.raises(ValueError, match="plain JSON"):
        canonical_json({"x": float("nan")})


def test_put_get_round_trip_and_read_only(tmp_path):
    cache = CellCache(tmp_path / "cells")
    ident = {"kind": "hog", "seed": 2}
    assert cache.get(ident) is None
    assert cache.get_or_compute(ident, lambda: {"ap": 0.25}) == {"ap": 0.25}
    assert cache.get(ident) == {"ap": 0.25} and len(cache) == 1
    assert cache.identities() == [ident]
    ro = CellCache(tmp_path / "cells", read_only=True)
    assert ro.get_or_compute({"kind": "cnn", "seed": 2}, lambda: pytest.fail("read-only cache computed")) is None
    assert not list((tmp_path / "cells").glob(".*.tmp"))  # no temporary left behind


def test_a_tampered_cell_is_refused(tmp_path):
    cache = CellCache(tmp_path)
    ident = {"kind": "hog"}
    p = cache.put(ident, 1)
    doc = json.loads(p.read_text())
    doc["identity"]["kind"] = "cnn"
    p.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="stored identity differs"):
        cache.get(ident)


def _worker(root, counter, start, out):
    cache = CellCache(root)

    def compute():
        with counter.get_lock():
            counter.value += 1
        time.sleep(0.5)  # long enough for the other process to arrive while this one computes
        return {"ap": 0.5}

    while time.time() < start:
        time.sleep(0.01)
    out.put(cache.get_or_compute({"cell": "same"}, compute))


def test_two_writers_compute_a_cell_once(tmp_path):
    ctx = mp.get_context("spawn")
    counter = ctx.Value("i", 0)
    out = ctx.Queue()
    start = time.time() + 3.0
    procs = [ctx.Process(target=_worker, args=(str(tmp_path), counter, start, out)) for _ in range(2)]
    for p in procs:
        p.start()
    results = [out.get(timeout=60) for _ in procs]
    for p in procs:
        p.join(timeout=60)
    assert results == [{"ap": 0.5}, {"ap": 0.5}]
    assert counter.value == 1
    assert len(CellCache(tmp_path)) == 1
