"""Fork-safe mesh rendering: OpenGL lives in a private, exec'd subprocess.

Why: a process that forks after creating a GL context deadlocks its children
(Mesa keeps driver threads and locks), and PyTorch's DataLoader forks its
workers. So :class:`Renderer` never creates a context in the calling process:
on first use it starts ``python -m synthaug.render._worker`` (fork+exec, a clean
interpreter) and sends it render requests over pipes. A Renderer that finds
itself in a forked child (its pid changed) starts a worker of its own; it
never touches the parent's pipes or context. EGL is used by default, OSMesa
if EGL cannot start (or when ``PYOPENGL_PLATFORM=osmesa``).

Example:
    >>> import numpy as np
    >>> with Renderer("quadcopter") as r:  # doctest: +SKIP
    ...     cov, nrm = r.layers(np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1), size=40)
"""

from __future__ import annotations

import os
import pickle
import select
import struct
import subprocess
import sys
import tempfile
import threading
from typing import Any

import numpy as np
import torch

from synthaug.render.mesh import load_mesh, mesh_fingerprint
from synthaug.render.pose import rotation_matrices

DEFAULT_OBJECT_SCALE = 0.7  # mesh unit length (its longest side) as a fraction of the patch side
_HEADER = struct.Struct("<Q")


def write_frame(stream: Any, obj: Any) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(_HEADER.pack(len(data)))
    stream.write(data)
    stream.flush()


def _read_exact(fd: int, n: int, timeout: float | None) -> bytes:
    chunks, got = [], 0
    while got < n:
        if timeout is not None:
            ready, _, _ = select.select([fd], [], [], timeout)
            if not ready:
                raise TimeoutError(f"render worker did not answer within {timeout:.0f} s")
        chunk = os.read(fd, min(n - got, 1 << 22))
        if not chunk:
            raise EOFError("render worker closed its output")
        chunks.append(chunk)
        got += len(chunk)
    return b"".join(chunks)


def read_frame_fd(fd: int, timeout: float | None = None) -> Any:
    (length,) = _HEADER.unpack(_read_exact(fd, _HEADER.size, timeout))
    return pickle.loads(_read_exact(fd, length, timeout))


class RenderError(RuntimeError):
    """The render worker failed; the message carries its error and log tail."""


class Renderer:
    """Exact object layers of one mesh, rendered offscreen in a private subprocess.

    Args:
        mesh: path, built-in name (``"quadcopter"``) or :class:`trimesh.Trimesh`
            (normalised to unit size on load).
        platform: ``"egl"`` or ``"osmesa"``; default: ``$PYOPENGL_PLATFORM`` or
            EGL with OSMesa as fallback.
        timeout: seconds to wait for one request before giving up.
    """

    def __init__(self, mesh: Any, *, platform: str | None = None, timeout: float = 300.0) -> None:
        self.mesh = load_mesh(mesh)
        self.fingerprint = mesh_fingerprint(self.mesh)
        if platform not in (None, "egl", "osmesa"):
            raise ValueError(f"platform must be 'egl' or 'osmesa', got {platform!r}")
        self.platform = platform or os.environ.get("PYOPENGL_PLATFORM") or "egl"
        self._explicit_platform = platform is not None or "PYOPENGL_PLATFORM" in os.environ
        self.timeout = timeout
        self._proc: subprocess.Popen | None = None
        self._pid: int | None = None
        self._log = None
        self._lock = threading.Lock()

    # ------------------------------------------------------------ process
    def _start(self, platform: str) -> None:
        env = dict(os.environ, PYOPENGL_PLATFORM=platform)
        self._log = tempfile.TemporaryFile()
        self._proc = subprocess.Popen(
            [sys.executable, "-m", "synthaug.render._worker"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._log, env=env, close_fds=True,
        )
        self._pid = os.getpid()
        try:
            write_frame(self._proc.stdin, {"op": "init", "vertices": np.asarray(self.mesh.vertices, np.float32),
                                           "faces": np.asarray(self.mesh.faces, np.int32)})
            reply = read_frame_fd(self._proc.stdout.fileno(), self.timeout)
        except (BrokenPipeError, EOFError, TimeoutError) as e:
            # the worker died or hung while starting: say how, with its own log (else the cause is lost)
            try:
                code = self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                code = None
            tail = self._log_tail()
            self._kill()
            raise RenderError(f"{e} (exit code {code})" + (f"; its log:\n{tail}" if tail.strip() else "")) from None
        if reply[0] != "ok":
            self._kill()
            raise RenderError(reply[1])

    def _ensure(self) -> None:
        if self._proc is not None and self._pid != os.getpid():
            # Forked child: the pipes and worker belong to the parent. Forget them.
            self._proc, self._log = None, None
        if self._proc is not None and self._proc.poll() is None:
            return
        try:
            self._start(self.platform)
        except (RenderError, EOFError) as first:
            if self._explicit_platform or self.platform == "osmesa":
                raise RenderError(f"cannot start an OpenGL renderer ({self.platform}): {first}") from None
            try:
                self._start("osmesa")
                self.platform = "osmesa"
            except (RenderError, EOFError) as second:
                raise RenderError(
                    f"cannot start an OpenGL renderer: EGL failed ({first}); OSMesa failed ({second})"
                ) from None

    def _log_tail(self) -> str:
        if self._log is None:
            return ""
        try:
            self._log.seek(0)
            return self._log.read().decode(errors="replace")[-2000:]
        except (OSError, ValueError):
            return ""

    def _kill(self) -> None:
        if self._proc is not None and self._pid == os.getpid():
            try:
                self._proc.kill()
                self._proc.wait(timeout=5)
            except Exception:
                pass
        self._proc = None

    def _request(self, msg: dict) -> Any:
        with self._lock:
            self._ensure()
            assert self._proc is not None
            try:
                write_frame(self._proc.stdin, msg)
                reply = read_frame_fd(self._proc.stdout.fileno(), self.timeout)
            except (BrokenPipeError, EOFError, TimeoutError) as e:
                tail = self._log_tail()
                self._kill()
                raise RenderError(f"render worker failed: {e}\n{tail}") from None
            if reply[0] != "ok":
                raise RenderError(reply[1])
            return reply[1]

    def close(self) -> None:
        with self._lock:
            if self._proc is not None and self._pid == os.getpid():
                try:
                    write_frame(self._proc.stdin, {"op": "quit"})
                    self._proc.wait(timeout=5)
                except Exception:
                    self._kill()
            self._proc = None

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass

    def __getstate__(self) -> dict:
        # pickled into spawn-started DataLoader workers: no process handles
        state = self.__dict__.copy()
        state.update(_proc=None, _pid=None, _log=None, _lock=None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._lock = threading.Lock()

    # ----------------------------------------------------------- rendering
    def render_views(self, rotations: np.ndarray, translations: np.ndarray | None = None, *, size: int,
                     scale: float = DEFAULT_OBJECT_SCALE, supersample: int = 2) -> tuple[np.ndarray, np.ndarray]:
        """Coverage (N, S, S) and camera-frame normals (N, 3, S, S) for given rotations."""
        rotations = np.asarray(rotations, np.float64)
        if rotations.ndim != 3 or rotations.shape[1:] != (3, 3):
            raise ValueError(f"rotations must be (N, 3, 3), got {rotations.shape}")
        if size < 1 or supersample < 1:
            raise ValueError(f"size and supersample must be >= 1, got {size}, {supersample}")
        if not 0 < scale <= 10:
            raise ValueError(f"scale must be in (0, 10], got {scale}")
        return self._request({"op": "render", "rotations": rotations,
                              "translations": None if translations is None else np.asarray(translations, np.float64),
                              "size": int(size), "scale": float(scale), "supersample": int(supersample)})

    def layers(self, alpha: Any, beta: Any, gamma: Any, t_x: Any, t_y: Any, *, size: int,
               scale: float = DEFAULT_OBJECT_SCALE, supersample: int = 2) -> tuple[torch.Tensor, torch.Tensor]:
        """Exact layers for poses (α, β, γ, t_x, t_y), each (N,) — see :mod:`synthaug.render.pose`.

        Returns:
            coverage (N, 1, S, S) and normals (N, 3, S, S) float32 tensors.
        """
        a, b, g, tx, ty = (np.atleast_1d(np.asarray(torch.as_tensor(v).detach().cpu(), np.float64))
                           for v in (alpha, beta, gamma, t_x, t_y))
        rot = rotation_matrices(a, b, g)
        cov, nrm = self.render_views(rot, np.stack([tx, ty], 1), size=size, scale=scale, supersample=supersample)
        return torch.from_numpy(cov)[:, None], torch.from_numpy(nrm)

    def render_params(self, theta: Any, *, size: int, scale: float = DEFAULT_OBJECT_SCALE,
                      supersample: int = 2) -> tuple[torch.Tensor, torch.Tensor]:
        """Exact layers for the pose part of a :class:`~synthaug.params.CaptureParams`."""
        return self.layers(theta.alpha, theta.beta, theta.gamma, theta.t_x, theta.t_y,
                           size=size, scale=scale, supersample=supersample)
