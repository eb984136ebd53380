"""Kill-safe long jobs (issue 18): a ``kill -9`` of ``synthaug fit --workers 2`` / ``synthaug ingest --workers 2``
leaves no worker and no resource tracker running, and the rerun gives the output of an uninterrupted run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

psutil = pytest.importorskip("psutil")

from synthaug.data.procedural import sky_backgrounds  # noqa: E402
from synthaug.data.seedset import write_seedset  # noqa: E402

REPO = Path(__file__).resolve().parents[1]


def _env():
    return {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONWARNINGS": "ignore", "PYOPENGL_PLATFORM": "egl"}


def _cli(*args):
    return [sys.executable, "-m", "synthaug.cli", *map(str, args)]


def _alive(pid):
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def _spawned_worker(cmdline: str) -> bool:
    return "spawn_main" in cmdline and "resource_tracker" not in cmdline


def _kill_when(cmd, ready, *, timeout=60.0, is_worker=_spawned_worker, grace=10.0):
    """Start ``cmd`` in its own session, wait until it has two workers (``is_worker(cmdline)``) and ``ready()``,
    SIGKILL it; return the pids of the children it had, and those still alive ``grace`` s later."""
    proc = subprocess.Popen(cmd, cwd=REPO, env=_env(), start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    children: set[int] = set()
    try:
        parent = psutil.Process(proc.pid)
        deadline = time.time() + timeout
        while time.time() < deadline and proc.poll() is None:
            try:
                kids = parent.children(recursive=True)
            except psutil.NoSuchProcess:
                break
            children |= {k.pid for k in kids}
            workers = [k for k in kids if is_worker(" ".join(_cmdline(k)))]
            if len(workers) >= 2 and ready():
                break
            time.sleep(0.05)
        assert proc.poll() is None, f"the command ended before the kill:\n{proc.stderr.read().decode()[-3000:]}"
        children |= {k.pid for k in parent.children(recursive=True)}
        assert len(children) >= 2, children
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        gone_by = time.time() + grace
        while time.time() < gone_by and any(_alive(p) for p in children):
            time.sleep(0.1)
        survivors = [p for p in children if _alive(p)]
        return children, survivors
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for p in children:  # never leave anything behind, even when the test fails
            if _alive(p):
                try:
                    os.kill(p, signal.SIGKILL)
                except ProcessLookupError:
                    pass


def _cmdline(p):
    try:
        return p.cmdline()
    except (psutil.NoSuchProcess, psutil.AccessDenied):
        return []


def _seedset(root, n=6):
    rng = np.random.default_rng(0)
    bgs = sky_backgrounds(n, (40, 40), seed=0)
    patches = bgs.copy()
    for i in range(n):
        yy, xx = np.mgrid[:40, :40]
        blob = ((xx - 20 - rng.integers(-3, 4)) ** 2 / 60 + (yy - 20) ** 2 / 12) < 1
        patches[i][blob] = 40
    frames = sky_backgrounds(n, (80, 80), seed=1)
    write_seedset(root / "seeds", patches=patches, backgrounds=bgs, boxes=[[20, 20, 28, 14]] * n,
                  centres=[[34, 27]] * n, crops=[[34, 27, 40]] * n,
                  records=[{"video": f"v{i}", "frame": i} for i in range(n)], frames=list(frames),
                  background_frames=list(frames), negatives=sky_backgrounds(8, (40, 40), seed=2),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    return root / "seeds"


@pytest.mark.slow
def test_kill_9_of_fit_leaves_no_process_and_the_rerun_gives_the_uninterrupted_file(tmp_path, caplog):
    import logging

    from synthaug.fit.fitting import FitConfig, fit_seedset

    seeds = _seedset(tmp_path)
    budget = 250
    cfg = FitConfig(budget=budget, step_deg=30.0, sprite_size=48)  # as the CLI parses it
    ref = fit_seedset(seeds, "quadcopter", tmp_path / "ref.json", cfg)  # also fills the sprite cache
    out = tmp_path / "fit.json"
    parts = tmp_path / ".fit.json.parts"
    cmd = _cli("fit", "--seeds", seeds, "--out", out, "--budget", budget, "--step-deg", 30, "--sprite-size", 48,
               "--workers", 2, "--lockstep", 1, "--no-progress")  # parts land one by one, so the kill falls between them
    children, survivors = _kill_when(cmd, lambda: len(list(parts.glob("seed_*.json"))) >= 1)
    assert survivors == [], [(p, _cmdline(psutil.Process(p))) for p in survivors if psutil.pid_exists(p)]
    done = len(list(parts.glob("seed_*.json")))
    assert 1 <= done < 6 and not out.exists(), done
    # resume (in this process: the file does not depend on the number of processes)
    caplog.set_level(logging.WARNING, logger="synthaug.fit")
    calls = []
    fit_seedset(seeds, "quadcopter", out, cfg, progress=lambda d, t: calls.append(d))
    assert len(calls) == 6 - done and not [r for r in caplog.records if r.name == "synthaug.fit"]  # parts reused
    assert out.read_text() == ref.read_text()


@pytest.mark.slow
def test_two_fits_into_one_output_take_turns_and_both_give_the_file(tmp_path):
    """Two ``synthaug fit`` runs into the same ``--out`` at once (e.g. two cells of one seed set in two processes),
    the second started once the first has fitted a seed: both succeed, with the same bytes. Before the output's
    lock, the second took the first's parts as done, the first removed them when it finished, and the second failed
    reading them (stop 101; a budget that keeps the first busy while the second starts)."""
    seeds = _seedset(tmp_path, n=4)
    out = tmp_path / "fit.json"
    parts = tmp_path / ".fit.json.parts"
    cmd = _cli("fit", "--seeds", seeds, "--out", out, "--budget", 6000, "--step-deg", 30, "--sprite-size", 48,
               "--lockstep", 1, "--no-progress")
    first = subprocess.Popen(cmd, cwd=REPO, env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    while time.time() < deadline and first.poll() is None and not list(parts.glob("seed_*.json")):
        time.sleep(0.05)
    assert first.poll() is None and list(parts.glob("seed_*.json")), "the first run's parts never landed"
    second = subprocess.Popen(cmd, cwd=REPO, env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    err = first.communicate(timeout=300)[1].decode()
    assert first.returncode == 0, err
    made_first = out.read_text()
    err = second.communicate(timeout=300)[1].decode()
    assert second.returncode == 0, err
    assert out.read_text() == made_first and not parts.exists()


@pytest.mark.slow
def test_kill_9_of_ingest_leaves_no_process_and_the_rerun_gives_the_uninterrupted_seed_set(tmp_path):
    from synthaug.data.seedset import SeedSet
    from synthaug.data.synthvideo import make_panning_video

    data = tmp_path / "data"
    for k in range(6):
        make_panning_video(data, n_frames=40, size=(256, 192), seed=10 + k, name=f"V_DRONE_{k + 1:03d}")
    opts = ["--seeds", 4, "--per-video", 3, "--patch-size", 24, "--negatives-per-video", 4, "--no-progress"]
    ref = subprocess.run(_cli("ingest", "--videos", data / "videos", "--labels", data / "labels",
                              "--out", tmp_path / "ref", "--workers", 1, *opts),
                         cwd=REPO, env=_env(), capture_output=True, text=True, timeout=120)
    assert ref.returncode == 0, ref.stderr[-3000:]
    out = tmp_path / "out"
    cmd = _cli("ingest", "--videos", data / "videos", "--labels", data / "labels", "--out", out, "--workers", 2,
               *opts)
    children, survivors = _kill_when(cmd, lambda: (out / "pool").is_dir())
    assert survivors == [], [(p, _cmdline(psutil.Process(p))) for p in survivors if psutil.pid_exists(p)]
    assert not (out / "seedsets").exists()
    rerun = subprocess.run(cmd, cwd=REPO, env=_env(), capture_output=True, text=True, timeout=120)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    report = json.loads(rerun.stdout)
    assert report["failed"] == {} and report["processed"] + report["skipped_current"] == 6
    a, b = SeedSet.load(tmp_path / "ref/seedsets/drone_4"), SeedSet.load(out / "seedsets/drone_4")
    assert [(r["video"], r["frame"]) for r in a.records] == [(r["video"], r["frame"]) for r in b.records]
    assert np.array_equal(a.patches, b.patches) and np.array_equal(a.backgrounds, b.backgrounds)
    assert np.array_equal(a.negatives, b.negatives)


@pytest.mark.parametrize("extra, match", [
    (["--step-deg", "0"], "argument --step-deg"),  # numbers are refused by argparse as it parses
    (["--effects", "rainbow"], "rainbow"),
    (["--budget", "3"], "argument --budget"),
])
def test_fit_option_errors_leave_nothing_behind(tmp_path, capsys, extra, match):
    from synthaug.cli import main

    seeds = _seedset(tmp_path, n=2)
    out = tmp_path / "o" / "fit.json"
    try:
        rc = main(["fit", "--seeds", str(seeds), "--out", str(out), "--no-progress", *extra])
    except SystemExit as e:
        rc = e.code
    assert rc == 2
    err = capsys.readouterr().err
    assert "synthaug fit:" in err and match in err and "Traceback" not in err
    assert not out.exists() and not (out.parent / ".fit.json.parts").exists()


def test_fit_into_a_directory_fails_before_any_work(tmp_path, capsys):
    from synthaug.cli import main

    seeds = _seedset(tmp_path, n=2)
    (tmp_path / "taken").mkdir()
    rc = main(["fit", "--seeds", str(seeds), "--out", str(tmp_path / "taken"), "--no-progress", "--budget", "20",
               "--step-deg", "30", "--sprite-size", "48"])
    assert rc == 2 and f"{tmp_path / 'taken'} is a directory" in capsys.readouterr().err
    assert not (tmp_path / ".taken.parts").exists()


@pytest.mark.slow
def test_kill_9_of_train_fit_leaves_no_dataloader_or_render_worker(tmp_path):
    """``python train/fit.py --config configs/cnn_tiny_synthetic.yaml`` with 2 DataLoader workers, SIGKILLed while it
    trains: every child (the forked DataLoader workers, any render worker) is gone within 10 s."""
    sys.path.insert(0, str(Path(__file__).parent))
    from test_refit import tiny_seedset

    seeds = tiny_seedset(tmp_path)
    log_root = tmp_path / "runs"
    cmd = [sys.executable, str(REPO / "train" / "fit.py"), "--config", str(REPO / "configs" / "cnn_tiny_synthetic.yaml"),
           "--data.init_args.seed_dir", str(seeds), "--data.init_args.params", "null",
           "--data.init_args.synthetic_per_real", "200", "--data.init_args.num_workers", "2",
           "--trainer.max_epochs", "1000", "--trainer.default_root_dir", str(log_root),
           "--trainer.logger.init_args.save_dir", str(log_root)]
    started = time.time()
    # forked DataLoader workers run the parent's command line; wait until two of them (and 2 s of training) exist
    children, survivors = _kill_when(cmd, lambda: time.time() - started > 2, timeout=180,
                                     is_worker=lambda c: "train/fit.py" in c)
    assert len(children) >= 2, children
    print(f"killed train/fit.py with {len(children)} children")
    assert survivors == [], f"children still running 10 s after the kill: {survivors}"


_PLAIN_LOADER = """
import sys
from torch.utils.data import DataLoader
import synthaug.data.synthetic
from synthaug import SyntheticObjectDataset
from synthaug.data.seedset import SeedSet

if sys.argv[2] == "unguarded":  # the control: the dataset's guard switched off (forked workers inherit it)
    synthaug.data.synthetic.guard_loader_worker = lambda: None
ds = SyntheticObjectDataset("quadcopter", SeedSet.load(sys.argv[1]), None, length=10 ** 6, patch_size=40)
for batch in DataLoader(ds, batch_size=20000, num_workers=2):  # a batch renders for tens of seconds
    pass
"""


@pytest.mark.slow
def test_kill_9_of_a_users_plain_dataloader_leaves_no_worker(tmp_path):
    """A user's own ``DataLoader`` over :class:`SyntheticObjectDataset` (no ``worker_init_fn``), SIGKILLed while its
    two forked workers render a long batch: both are gone within 3 s (the dataset's ``guard_loader_worker``); with
    the guard switched off (the control) a worker is still rendering 3 s after the kill, as PyTorch's workers look
    for their parent only between batches."""
    seeds = _seedset(tmp_path)
    script = tmp_path / "plain_loader.py"
    script.write_text(_PLAIN_LOADER)
    survivors = {}
    for mode in ("guarded", "unguarded"):
        seen: list[float] = []  # when both workers were first seen: killed 3 s into their first batch

        def rendering() -> bool:
            seen.append(time.time())
            return seen[-1] - seen[0] > 3

        children, survivors[mode] = _kill_when([sys.executable, str(script), str(seeds), mode], rendering,
                                               timeout=120, is_worker=lambda c: "plain_loader.py" in c, grace=3.0)
        assert len(children) >= 2, (mode, children)
    assert survivors["guarded"] == [], f"workers still running 3 s after the kill: {survivors['guarded']}"
    assert survivors["unguarded"], "the control's workers died by themselves: the test cannot tell the guard's work"
