"""Diagnosis of the simulation against measured data (issue 6).

:mod:`synthaug.diagnose.reference_camera` — the measured-data simulator: seed
sets rendered through a richer camera with chosen effects hidden, the truth
stored beside them, optionally with nuisances that are not camera effects
(:class:`~synthaug.diagnose.nuisances.Nuisances`: material, light, real mesh,
a moving scene). (Residual analysis, model extension and the
``synthaug diagnose`` report build on it.)
"""

from __future__ import annotations

from typing import Any

__all__ = ["make_measured_seedset", "seed_geometry", "load_truth", "REALISTIC_STRENGTHS", "REALISTIC_RANGES",
           "OUTSIDE_EFFECTS", "Nuisances"]


def __getattr__(name: str) -> Any:
    # lazy: the simulator imports the renderer's cache and OpenCV only when used
    if name in __all__:
        from synthaug.diagnose import reference_camera

        return getattr(reference_camera, name)
    raise AttributeError(f"module 'synthaug.diagnose' has no attribute {name!r}")
