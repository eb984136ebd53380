"""synthaug — synthetic training images for object detectors (Rozantsev et al., CVIU 2015).

Importing the package is cheap: no GL context, no pyrender or OpenCV import.
Public names are resolved lazily.

Example:
    >>> import synthaug
    >>> synthaug.CaptureParams.vector_names()[:5]
    ['alpha', 'beta', 'gamma', 't_x', 't_y']
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from typing import Any

__version__ = "0.1.0"

_LAZY = {
    "CaptureParams": "synthaug.params",
    "ParamSpec": "synthaug.params",
    "SyntheticObjectDataset": "synthaug.data.synthetic",
    "RealismCritic": "synthaug.detectors.critic",
    "ViewCache": "synthaug.render.cache",
    "Renderer": "synthaug.render.server",
    "load_mesh": "synthaug.render.mesh",
    "make_quadcopter": "synthaug.render.mesh",
    "simulate": "synthaug.effects.pipeline",
    "CaptureEffects": "synthaug.effects.transform",
    "register_effect": "synthaug.effects.registry",
    "Effect": "synthaug.effects.registry",
    "list_effects": "synthaug.effects.registry",
}

__all__ = sorted(_LAZY) + ["__version__"]


def _no_triton_after_gl() -> None:
    """Keep triton out of a process that already uses OpenGL (measured: it segfaults).

    torch's CUDA wheels ship triton, and importing torchvision imports
    ``torch._dynamo``, which imports triton. Triton's library carries its own
    LLVM; loaded *after* Mesa's llvmpipe driver has loaded its LLVM (any
    pyrender/EGL render in this process) the process dies with SIGSEGV. If
    OpenGL is already imported and triton is not, triton is marked absent
    (``sys.modules["triton"] = None``: torch then reports no triton; on a CPU
    or EGL-rendering process nothing uses it). Importing torchvision before
    any GL work avoids the problem altogether. synthaug itself never makes a
    GL context in the calling process (its renders run in an exec'd worker).
    """
    if "OpenGL" in sys.modules and "triton" not in sys.modules and importlib.util.find_spec("triton") is not None:
        sys.modules["triton"] = None  # type: ignore[assignment]


_no_triton_after_gl()


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'synthaug' has no attribute {name!r}")


def __dir__() -> list[str]:
    return __all__
