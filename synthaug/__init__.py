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
from typing import Any

__version__ = "0.1.0"

_LAZY = {
    "CaptureParams": "synthaug.params",
    "ParamSpec": "synthaug.params",
    "SyntheticObjectDataset": "synthaug.data.synthetic",
    "ViewCache": "synthaug.render.cache",
    "Renderer": "synthaug.render.server",
    "load_mesh": "synthaug.render.mesh",
    "make_quadcopter": "synthaug.render.mesh",
    "simulate": "synthaug.effects.pipeline",
    "register_effect": "synthaug.effects.registry",
    "Effect": "synthaug.effects.registry",
    "list_effects": "synthaug.effects.registry",
}

__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'synthaug' has no attribute {name!r}")


def __dir__() -> list[str]:
    return __all__
