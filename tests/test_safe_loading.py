"""Issue 18, item 4, "safe loading stays safe": every loader of a file a user hands in refuses a malicious pickle.

The malicious object's ``__reduce__`` would run ``open(MARKER, "w")`` when unpickled; each test asserts the
loader raises a clear error naming the file AND that the marker was never created (nothing was executed).
Routes: ``load_detector``, ``load_patch_cnn`` (save_detector files and Lightning checkpoints, hence the ``cnn``
and weak-learner distances), ``synthaug detect --checkpoint``, ``train/detector_tv.load_detector_tv``,
``train/fit.py --ckpt_path`` (Lightning's own loader), ``load_npz`` / ``SeedSet.load`` (object arrays in the npz),
the view cache's ``.npy`` files, and YAML configs (safe loaders only: a ``!!python/object`` tag is refused).
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

REPO = Path(__file__).resolve().parents[1]


class Evil:
    """Unpickling this creates ``marker`` (a stand-in for arbitrary code)."""

    def __init__(self, marker: Path):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


@pytest.fixture
def marker(tmp_path):
    m = tmp_path / "MARKER"
    yield m
    assert not m.exists(), "the malicious pickle was executed"


def _evil_torch(path: Path, marker: Path, *, lightning: bool = False) -> Path:
    if lightning:  # shaped like a Lightning checkpoint of PatchDetectorModule
        payload = {"state_dict": {"net.w": torch.zeros(1)}, "hyper_parameters": {"window": Evil(marker)},
                   "epoch": 0, "global_step": 0, "pytorch-lightning_version": "2.6.0"}
    else:  # shaped like a save_detector file
        payload = {"format": "synthaug.detector", "version": 1, "kind": "hog", "state": {"x": Evil(marker)}}
    torch.save(payload, path)
    assert not marker.exists()
    return path


def test_the_marker_would_be_created_by_a_plain_unpickle(tmp_path):
    """The fixture is live: ``weights_only=False`` runs it (so the other tests prove refusal, not a dud)."""
    m = tmp_path / "MARKER"
    path = _evil_torch(tmp_path / "evil.pt", m)
    torch.load(path, weights_only=False)
    assert m.exists()


def test_load_detector_refuses_a_malicious_pickle(tmp_path, marker):
    from synthaug.detectors.base import load_detector

    path = _evil_torch(tmp_path / "evil.pt", marker)
    with pytest.raises(ValueError, match=re.escape(str(path))):
        load_detector(path)


@pytest.mark.parametrize("lightning", [False, True], ids=["save_detector-file", "lightning-ckpt"])
def test_load_patch_cnn_refuses_a_malicious_pickle(tmp_path, marker, lightning):
    from synthaug.detectors.cnn import load_patch_cnn

    path = _evil_torch(tmp_path / ("evil.ckpt" if lightning else "evil.pt"), marker, lightning=lightning)
    with pytest.raises(ValueError, match=re.escape(str(path))):
        load_patch_cnn(path)


def test_cnn_distance_checkpoint_refuses_a_malicious_pickle(tmp_path, marker):
    """The ``cnn`` distance reads its checkpoint through load_patch_cnn."""
    from synthaug.distances import cnn as cnn_distance

    path = _evil_torch(tmp_path / "evil.ckpt", marker, lightning=True)
    with pytest.raises(ValueError, match=re.escape(str(path))):
        cnn_distance.load_patch_cnn(path)


def test_detect_cli_refuses_a_malicious_checkpoint(tmp_path, marker, capsys):
    from PIL import Image

    from synthaug.cli import main

    frames = tmp_path / "frames"
    frames.mkdir()
    Image.fromarray(np.zeros((48, 64), np.uint8)).save(frames / "f0.png")
    path = _evil_torch(tmp_path / "evil.pt", marker)
    out = tmp_path / "dets.json"
    try:
        rc = main(["detect", "--images", str(frames), "--checkpoint", str(path), "--out", str(out)])
    except SystemExit as e:
        rc = e.code
    err = capsys.readouterr().err
    assert rc == 2, err
    line = err.strip().splitlines()[-1]
    assert str(path) in line and "pickled code" in line, err
    assert "Traceback" not in err
    assert not out.exists()


def test_detector_tv_loader_refuses_a_malicious_pickle(tmp_path, marker):
    spec = importlib.util.spec_from_file_location("synthaug_train_detector_tv", REPO / "train" / "detector_tv.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    path = tmp_path / "detector_tv.pt"
    torch.save({"w": Evil(marker)}, path)
    path.with_suffix(".json").write_text(json.dumps({}))
    with pytest.raises(Exception) as info:
        mod.load_detector_tv(path)
    assert "weights_only" in str(info.value) or "Unsupported global" in str(info.value), info.value


def _evil_npz(path: Path, marker: Path, key: str = "patches") -> Path:
    np.savez(path, **{key: np.array([Evil(marker), 1], dtype=object)})
    assert not marker.exists()
    return path


def test_load_npz_refuses_object_arrays(tmp_path, marker):
    from synthaug.data.seedset import load_npz

    path = _evil_npz(tmp_path / "arrays.npz", marker)
    with pytest.raises(ValueError, match=re.escape(str(path))) as info:
        load_npz(path)
    assert "pickled" in str(info.value)


def test_seedset_load_refuses_an_npz_with_object_arrays(tmp_path, marker):
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import ARRAYS, SeedSet, write_seedset

    bgs = sky_backgrounds(2, (40, 40), seed=0)
    frames = sky_backgrounds(2, (64, 64), seed=1)
    write_seedset(tmp_path / "seeds", patches=bgs.copy(), backgrounds=bgs, boxes=[[0, 0, 10, 10]] * 2,
                  centres=[[5, 5]] * 2, crops=[[5, 5, 14]] * 2, records=[{"video": "v"}] * 2,
                  frames=list(frames), background_frames=list(frames),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    SeedSet.load(tmp_path / "seeds")  # valid before the swap
    arrays = tmp_path / "seeds" / ARRAYS
    with np.load(arrays) as z:
        kept = {k: z[k] for k in z.files}
    kept["patches"] = np.array([Evil(marker), Evil(marker)], dtype=object)
    np.savez(arrays, **kept)
    assert arrays.exists() and not marker.exists()
    with pytest.raises(ValueError, match=re.escape(str(arrays))):
        SeedSet.load(tmp_path / "seeds")


def test_view_cache_npy_with_object_arrays_is_refused(tmp_path, marker):
    """A tampered cache entry is not unpickled: ``_load`` raises ValueError (the caller then rebuilds the entry)."""
    from synthaug.render.cache import CACHE_VERSION, ViewCache

    folder = tmp_path / "entry"
    folder.mkdir()
    (folder / "meta.json").write_text(json.dumps({"version": CACHE_VERSION, "sprite_scale": 1.0, "fingerprint": "x"}))
    for name in ("coverage", "normals"):
        np.save(folder / f"{name}.npy", np.zeros((1, 2, 2), np.float32))
    np.save(folder / "alphas.npy", np.array([Evil(marker)], dtype=object), allow_pickle=True)
    np.save(folder / "betas.npy", np.zeros(1))
    assert not marker.exists()
    with pytest.raises(ValueError):
        ViewCache._load(folder)


def test_yaml_is_read_with_safe_loaders_only():
    """No ``yaml.load(`` / ``yaml.unsafe_load`` / ``yaml.full_load`` / ``Loader=yaml.Loader`` in the package or train/."""
    bad = re.compile(r"yaml\.(unsafe_load|full_load|load_all|load)\s*\(|Loader\s*=\s*yaml\.(Unsafe|Full)?Loader\b")
    hits = [f"{p.relative_to(REPO)}:{i}: {line.strip()}"
            for folder in ("synthaug", "train", "benchmarks") for p in (REPO / folder).rglob("*.py")
            for i, line in enumerate(p.read_text().splitlines(), 1)
            if bad.search(line) and "SafeLoader" not in line]
    assert hits == []


def _train_fit(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONWARNINGS": "ignore", "OMP_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, str(REPO / "train" / "fit.py"), *args], cwd=tmp_path,
                          capture_output=True, text=True, timeout=240, env=env)


@pytest.mark.slow
def test_train_fit_yaml_config_with_a_python_tag_is_refused(tmp_path, marker):
    """LightningCLI (jsonargparse) parses the YAML config with a safe loader: a ``!!python`` tag is never built."""
    cfg = (REPO / "configs" / "cnn_tiny.yaml").read_text()
    cfg = cfg.replace("seed_everything: 0", f"seed_everything: !!python/object/apply:builtins.open ['{marker}', 'w']")
    path = tmp_path / "evil.yaml"
    path.write_text(cfg)
    proc = _train_fit(tmp_path, "fit", "--config", str(path), "--trainer.default_root_dir", str(tmp_path),
                      "--trainer.logger.init_args.save_dir", str(tmp_path), "--trainer.max_epochs", "1")
    assert proc.returncode != 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert not list(tmp_path.glob("lightning_logs/version_*/checkpoints/*.ckpt"))


@pytest.mark.slow
def test_train_fit_ckpt_path_refuses_a_malicious_checkpoint(tmp_path, marker):
    """``train/fit.py fit --ckpt_path`` (Lightning's resume loader) refuses a checkpoint that holds pickled code."""
    path = _evil_torch(tmp_path / "evil.ckpt", marker, lightning=True)
    proc = _train_fit(tmp_path, "fit", "--config", str(REPO / "configs" / "cnn_tiny.yaml"),
                      "--trainer.default_root_dir", str(tmp_path), "--trainer.logger.init_args.save_dir", str(tmp_path),
                      "--trainer.max_epochs", "1", "--data.init_args.generated_positives", "20",
                      "--data.init_args.generated_negatives", "20", "--ckpt_path", str(path))
    assert proc.returncode != 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "weights_only" in proc.stderr or "Unsupported global" in proc.stderr, proc.stderr[-3000:]
