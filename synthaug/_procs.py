"""Worker processes that die with their parent.

A ``kill -9`` of a command that runs a process pool (``synthaug fit --workers``,
``synthaug ingest --workers``) gives its workers no chance to be told: they
would run on, orphaned, for as long as their task lasts, and the
multiprocessing resource tracker with them. :func:`die_with_parent`, called in
each worker's initializer, ends the worker when its parent is gone:

* on Linux, ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` asks the kernel to kill it
  the moment its parent dies;
* everywhere, a daemon thread polls ``os.getppid()`` (once a second by
  default) and exits the process when the parent changed (the fallback, and
  the guard where PDEATHSIG does not fire, e.g. when the parent *thread*
  that started the worker lives on but the process was re-parented).

The resource tracker exits by itself once the parent and every worker are gone
(its pipe closes). Use :func:`pool_kwargs` for a ``ProcessPoolExecutor``, and
:func:`loader_worker_init` for a ``DataLoader``: PyTorch's own workers look for
their parent only between batches (every 5 s while idle), so a worker busy
rendering a batch outlived a ``kill -9`` of ``train/fit.py`` by over 10 s on a
loaded machine (stop 100: ``tests/test_kill_safe.py`` in a full suite run).
A user's own ``DataLoader`` has no such ``worker_init_fn``:
:class:`~synthaug.data.synthetic.SyntheticObjectDataset` calls
:func:`guard_loader_worker` on every batch, which does the same once per
worker process.
"""

from __future__ import annotations

import functools
import os
import signal
import sys
import threading
import time
from typing import Any, Callable

__all__ = ["die_with_parent", "pool_kwargs", "worker_initializer", "loader_worker_init", "guard_loader_worker"]

PR_SET_PDEATHSIG = 1
_guarded_pid: int | None = None  # the process whose guard is set (a forked child inherits the parent's value)


def _set_pdeathsig(sig: int = signal.SIGKILL) -> bool:
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0) == 0
    except Exception:  # pragma: no cover (no libc / no prctl)
        return False


def die_with_parent(parent_pid: int | None = None, *, poll_s: float = 1.0) -> None:
    """End this process when ``parent_pid`` (default: the current parent) is no longer its parent.

    Args:
        parent_pid: the parent's pid as the parent saw it (pass ``os.getpid()`` from
            the parent: a parent that died before this call is caught too).
        poll_s: the watchdog thread's polling period (seconds).
    """
    global _guarded_pid
    parent = os.getppid() if parent_pid is None else int(parent_pid)
    _guarded_pid = os.getpid()
    _set_pdeathsig()
    if os.getppid() != parent:  # the parent died before the prctl
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(poll_s)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="synthaug-parent-watchdog", daemon=True).start()


def worker_initializer(parent_pid: int, init: Callable[[], Any] | None = None) -> None:
    """A pool initializer: :func:`die_with_parent`, then ``init()`` (picklable, module level)."""
    die_with_parent(parent_pid)
    if init is not None:
        init()


def pool_kwargs(init: Callable[[], Any] | None = None) -> dict[str, Any]:
    """``initializer`` / ``initargs`` for a ``ProcessPoolExecutor`` whose workers die with this process."""
    return {"initializer": worker_initializer, "initargs": (os.getpid(), init)}


def _loader_worker(parent_pid: int, worker_id: int) -> None:
    die_with_parent(parent_pid)


def loader_worker_init() -> Callable[[int], None]:
    """A ``DataLoader`` ``worker_init_fn`` whose workers die with this process (the one that builds the loader and
    iterates it), picklable for any start method.

    Example:
        >>> init = loader_worker_init()
        >>> init.args == (os.getpid(),)
        True
    """
    return functools.partial(_loader_worker, os.getpid())


def guard_loader_worker() -> None:
    """In a ``DataLoader`` worker, :func:`die_with_parent` (the parent: the process iterating the loader), once per
    worker process; nothing elsewhere, nor where the loader's ``worker_init_fn`` (:func:`loader_worker_init`)
    already did it. :class:`~synthaug.data.synthetic.SyntheticObjectDataset` calls it on each batch, so that a
    user's plain ``DataLoader`` gets it too."""
    if _guarded_pid == os.getpid():
        return
    import torch.utils.data

    if torch.utils.data.get_worker_info() is not None:
        die_with_parent()
