"""One home for the versioned-file header check (issue 17): ``check_header`` / ``read_versioned_json`` and the
seven readers that use it, each refusing another format and another version with a message naming the file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch

from synthaug._io import check_header, read_versioned_json

SPEC = dict(format="synthaug.thing", version=1, what="thing file")


# ------------------------------------------------------------ check_header on hand-written documents
def test_check_header_accepts_and_returns_a_dict_copy():
    doc = {"format": "synthaug.thing", "version": 1, "x": [1]}
    out = check_header(doc, **SPEC, source="t.json")
    assert out == doc and isinstance(out, dict)
    out["y"] = 2
    assert "y" not in doc  # the caller may pop from the result without touching its input


@pytest.mark.parametrize("doc, message", [
    ({"format": "synthaug.other", "version": 1},
     r"^t\.json is not a synthaug thing file \(format 'synthaug\.other', expected 'synthaug\.thing'\)$"),
    ({"version": 1}, r"^t\.json is not a synthaug thing file \(format no 'format' field, expected 'synthaug\.thing'\)$"),
    ({"format": None, "version": 1}, r"format None, expected"),
    ({"format": "synthaug.thing", "version": 2},
     r"^t\.json: unsupported version 2 of a synthaug thing file \(this synthaug reads 1\)$"),
    ({"format": "synthaug.thing", "version": "1"}, r"unsupported version '1' of a synthaug thing file"),
    ({"format": "synthaug.thing"}, r"^t\.json: unsupported version no 'version' field of a synthaug thing file"),
    ([1, 2], r"^t\.json is not a synthaug thing file \(expected a mapping with a 'format' field, got list\)$"),
    (None, r"is not a synthaug thing file .*got NoneType"),
    ("text", r"is not a synthaug thing file .*got str"),
])
def test_check_header_failure_modes(doc, message):
    with pytest.raises(ValueError, match=message):
        check_header(doc, **SPEC, source="t.json")


def test_check_header_format_is_checked_before_version_and_source_is_optional():
    with pytest.raises(ValueError, match="^is not a synthaug thing file .*format 'x'"):
        check_header({"format": "x", "version": 9}, **SPEC)
    with pytest.raises(ValueError, match="^unsupported version 9 of a synthaug thing file"):
        check_header({"format": "synthaug.thing", "version": 9}, **SPEC)


def test_check_header_other_keys_and_unchecked_fields():
    assert check_header({"version": 3}, format=None, version=3, what="cache")["version"] == 3  # version only
    assert check_header({"format": "f"}, format="f", version=None, version_key=None, what="x") == {"format": "f"}
    meta = {"result_format": "synthaug.fit", "result_version": 2}
    with pytest.raises(ValueError, match=r"^m: unsupported result_version 2 of a synthaug fit result"):
        check_header(meta, format="synthaug.fit", version=1, what="fit result", source="m",
                     format_key="result_format", version_key="result_version")
    with pytest.raises(ValueError, match=r"result_format 'synthaug\.x', expected 'synthaug\.fit'"):
        check_header({**meta, "result_format": "synthaug.x"}, format="synthaug.fit", version=2, what="fit result",
                     format_key="result_format", version_key="result_version")


def test_read_versioned_json_names_the_file(tmp_path):
    f = tmp_path / "t.json"
    with pytest.raises(FileNotFoundError, match=f"^thing file not found: {f}$"):
        read_versioned_json(f, **SPEC)
    f.write_text("{not json")
    with pytest.raises(ValueError, match=rf"^{f} is not a JSON thing file \("):
        read_versioned_json(f, **SPEC)
    f.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ValueError, match="is not a JSON thing file"):
        read_versioned_json(f, **SPEC)
    f.write_text(json.dumps({"format": "synthaug.thing", "version": 7}))
    with pytest.raises(ValueError, match=rf"^{f}: unsupported version 7 of a synthaug thing file"):
        read_versioned_json(f, **SPEC)
    f.write_text(json.dumps({"format": "synthaug.thing", "version": 1, "a": 1}))
    assert read_versioned_json(f, **SPEC)["a"] == 1


# ------------------------------------------------------------ the seven readers
def _json(path: Path, doc) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc))
    return path


def _refuses(load, path: Path, good: dict, *, what: str, format_key: str = "format", version_key: str = "version",
             checks_format: bool = True) -> None:
    """``load(path)`` refuses ``good`` with another format and with another version, naming ``path``."""
    if checks_format:
        _json(path, {**good, format_key: "synthaug.other"})
        with pytest.raises(ValueError, match=rf"{path.name} is not a synthaug {what} \({format_key} 'synthaug.other'"):
            load(path)
    _json(path, {**good, version_key: 99})
    with pytest.raises(ValueError, match=rf"{path.name}: unsupported {version_key} 99 of a synthaug {what} "
                                         r"\(this synthaug reads"):
        load(path)


def test_capture_parameter_file_refuses_other_format_and_version(tmp_path):
    from synthaug.params import FIT_RESULT_FORMAT, FORMAT_NAME, FORMAT_VERSION, CaptureParams

    f = tmp_path / "p.json"
    CaptureParams.default(2).save(f, metadata={"result_format": FIT_RESULT_FORMAT, "result_version": 1})
    good = json.loads(f.read_text())
    assert CaptureParams.load(f).batch_size == 2
    assert good["format"] == FORMAT_NAME and good["version"] == FORMAT_VERSION
    _refuses(CaptureParams.load, f, good, what="capture-parameter file")
    # the fit result inside the metadata has its own version
    _json(f, {**good, "metadata": {"result_format": FIT_RESULT_FORMAT, "result_version": 5}})
    with pytest.raises(ValueError, match=r"p\.json: unsupported result_version 5 of a synthaug fit result"):
        CaptureParams.load(f)
    _json(f, {**good, "metadata": {"result_format": "someone.else", "result_version": 5}})  # not ours: not checked
    assert CaptureParams.load(f).batch_size == 2


def test_seed_set_refuses_other_format_and_version(tmp_path):
    from synthaug.data.seedset import FORMAT_NAME, FORMAT_VERSION, HEADER, SeedSet

    good = {"format": FORMAT_NAME, "version": FORMAT_VERSION, "records": []}
    _refuses(lambda p: SeedSet.load(p.parent), tmp_path / "s" / HEADER, good, what="seed set")


def test_split_file_refuses_other_format_and_version(tmp_path):
    from synthaug.data.splits import FORMAT_NAME, FORMAT_VERSION, load_split

    good = {"format": FORMAT_NAME, "version": FORMAT_VERSION, "train": ["a"], "val": [], "test": ["b"]}
    assert load_split(_json(tmp_path / "split.json", good)).videos["train"] == ["a"]
    _refuses(load_split, tmp_path / "split.json", good, what="split file")
    with pytest.raises(FileNotFoundError, match="split file not found"):
        load_split(tmp_path / "missing.json")


def test_detector_checkpoint_refuses_other_format_and_version(tmp_path):
    from synthaug.detectors.base import FORMAT_NAME, FORMAT_VERSION, load_detector

    f = tmp_path / "det.pt"
    torch.save({"format": "synthaug.other", "version": FORMAT_VERSION, "kind": "hog", "state": {}}, f)
    with pytest.raises(ValueError, match=r"det\.pt is not a synthaug detector checkpoint \(format 'synthaug.other'"):
        load_detector(f)
    torch.save({"format": FORMAT_NAME, "version": 99, "kind": "hog", "state": {}}, f)
    with pytest.raises(ValueError, match=r"det\.pt: unsupported version 99 of a synthaug detector checkpoint"):
        load_detector(f)
    torch.save([1, 2], f)
    with pytest.raises(ValueError, match=r"det\.pt is not a synthaug detector checkpoint .*got list"):
        load_detector(f)


def test_protocol_result_refuses_other_format_and_version(tmp_path):
    from synthaug.evaluate.results import RESULT_FORMAT, RESULT_VERSION, ProtocolResult

    good = {"format": RESULT_FORMAT, "version": RESULT_VERSION}
    _refuses(ProtocolResult.load, tmp_path / "r.json", good, what="protocol result")
    with pytest.raises(ValueError, match="^unsupported version 99 of a synthaug protocol result"):
        ProtocolResult.from_json({**good, "version": 99})
    with pytest.raises(ValueError, match="^is not a synthaug protocol result"):
        ProtocolResult.from_json({**good, "format": "x"})
    with pytest.raises(ValueError, match=r"^cell 3: unsupported version 99"):
        ProtocolResult.from_json({**good, "version": 99}, source="cell 3")


def test_cell_cache_refuses_another_cell_format(tmp_path):
    from synthaug.evaluate.cells import CELL_FORMAT, CellCache

    cache = CellCache(tmp_path)
    ident = {"kind": "hog", "seed": 0}
    p = cache.put(ident, {"ap": 0.5})
    good = json.loads(p.read_text())
    assert good["format"] == CELL_FORMAT
    _refuses(lambda _: cache.get(ident), p, good, what="experiment cell", version_key="format", checks_format=False)


def test_view_cache_refuses_another_version_and_rebuilds(tmp_path):
    from synthaug.render.cache import CACHE_VERSION, ViewCache

    folder = tmp_path / "views" / "v0_entry"
    good = {"version": CACHE_VERSION, "sprite_scale": 1.0, "fingerprint": "x"}
    _refuses(lambda f: ViewCache._load(f.parent), folder / "meta.json", good, what="view cache", checks_format=False)
    _json(folder / "meta.json", [good])
    with pytest.raises(ValueError, match="is not a synthaug view cache"):  # ViewCache.build rebuilds on ValueError
        ViewCache._load(folder)


# ------------------------------------------------------------ exclusive_lock in a spawned worker
_POOL_SCRIPT = '''
import multiprocessing as mp
import sys
from concurrent.futures import ProcessPoolExecutor

from synthaug._io import exclusive_lock


def square(x):
    return x * x


def work():
    with exclusive_lock(sys.argv[1]):  # the parent holds the lock while its pool works
        with ProcessPoolExecutor(1, mp_context=mp.get_context("spawn")) as ex:
            print(list(ex.map(square, [3])))


{call}
'''


@pytest.mark.parametrize("guarded", [True, False])
def test_exclusive_lock_refuses_a_spawned_worker_importing_the_main_script(tmp_path, guarded):
    """A script without a ``__main__`` guard that takes a lock and starts a spawn pool: each worker imports the
    script again and reaches the lock its parent holds. Without the check it waits forever (the parent waits on
    the worker); with it the worker fails at once, the pool breaks and the message names the guard."""
    import subprocess
    import sys

    call = 'if __name__ == "__main__":\n    work()' if guarded else "work()"
    script = tmp_path / "job.py"
    script.write_text(_POOL_SCRIPT.format(call=call))
    done = subprocess.run([sys.executable, str(script), str(tmp_path / "cell.lock")], capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    if guarded:
        assert done.returncode == 0 and done.stdout.strip() == "[9]", done.stderr
    else:
        assert done.returncode != 0 and "BrokenProcessPool" in done.stderr
        assert "spawned worker process imports its parent's main script" in done.stderr
        assert 'if __name__ == "__main__":' in done.stderr
