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
"""

from __future__ import annotations

import functools
import os
import signal
import sys
import threading
import time
from typing import Any, Callable

__all__ = ["die_with_parent", "pool_kwargs", "worker_initializer", "loader_worker_init"]

PR_SET_PDEATHSIG = 1


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
    parent = os.getppid() if parent_pid is None else int(parent_pid)
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

