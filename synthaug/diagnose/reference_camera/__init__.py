"""The measured-data simulator ("reference camera"): seed sets like real ones, with known hidden effects.

Diagnosis (issue 6) must find what the simulation S(Θ, B) misses. To test
it, this module makes *measured data* whose truth is known: whole camera
frames with an object at a random place and size, captured through a richer
camera than the model's, with any chosen candidate effects switched on
("hidden"), then cut into a seed set in the exact
:func:`~synthaug.data.seedset.write_seedset` format, so ``SeedSet.load`` and
``synthaug fit`` read it like an ingested one.

Per seed:

1. a scene background b (procedural sky, or given frames) and a pose, size
   and place of the object, rendered through a view cache of the *real* mesh
   (which may differ from the coarse mesh the fit gets: ``mesh_perturbation``);
2. object-only physics on the object layers: Lambert material w_d (or, with
   ``nuisances``, the case's own material under its video's light:
   :func:`~synthaug.diagnose.nuisances.shade_object`; the frame's scene then
   may also drift against the background's), hidden
   ``specular`` (with ``nuisances``, on that material: its video's light,
   direction and strength, and its smooth normals), ``rotor_blur`` (true
   rotor parts of the built-in quadcopter), the paper's motion blur, hidden
   ``rolling_shutter`` (along the motion direction), the out-of-list
   ``interlacing``; overlay on b, then the paper's
   boundary blur and object noise (all at frame scale);
3. the camera on the WHOLE frame, in physical order: haze → defocus →
   chromatic aberration → lens distortion → vignetting → exposure → white
   balance → sensor noise (read + shot) → tone curve → sharpening → 8-bit →
   JPEG (OpenCV's real codec);
4. the background frame B through the SAME camera without the object (its
   noise reduced by ``background_noise_factor``, as an aligned median of
   several frames is), so B_i contains the whole-frame effects exactly as
   with real data;
5. the box of the object's (geometrically warped) coverage, then object and
   background patches with :func:`~synthaug.data.seedset.crop_patch`.

One module a concept: :mod:`.settings` (what can be hidden, and how strongly), :mod:`.real_object`
(the filmed mesh), :mod:`.simulate` (the checked arguments, each seed's frozen record
:class:`~synthaug.diagnose.reference_camera.simulate.MeasuredSeed` drawn first, then steps 1, 2 and 5),
:mod:`.capture` (steps 3 and 4, the whole-frame camera) and :mod:`.truth` (what a fit should recover).

The truth is stored: the header's ``reference_camera`` block (hidden effects
and their settings, mesh, noise, ranges), each record's ``truth`` (Θ in patch
units, the hidden parameters actually used, object size and place) and
``truth.json``, a :class:`~synthaug.params.CaptureParams` file over
``PAPER_EFFECTS + hidden`` with per-seed ``object_scale``, ``origin``,
``frame_size`` and ``frame_scale`` extras, which is what a fit should recover.

Example:
    >>> import tempfile, os
    >>> from synthaug.data.seedset import SeedSet
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = make_measured_seedset(os.path.join(d, "m"), n_seeds=2, hidden={"vignetting": {"vignette_k": 0.3}},
    ...                               frame_size=(96, 128), object_px=(16, 20), view_step_deg=30, sprite_size=48)
    ...     s = SeedSet.load(p)
    ...     len(s), s.patches.shape, s.metadata["reference_camera"]["hidden"]
    (2, (2, 40, 40), {'vignetting': {'vignette_k': 0.3}})
"""

from __future__ import annotations

from synthaug.data.seedset import seed_geometry  # re-exported (it lives next to crop_patch)
from synthaug.diagnose.nuisances import Nuisances
from synthaug.diagnose.reference_camera.capture import column_gains, wb_gains
from synthaug.diagnose.reference_camera.real_object import perturb_mesh, quadcopter_parts
from synthaug.diagnose.reference_camera.settings import (
    OBJECT_ONLY_EFFECTS,
    OUTSIDE_EFFECTS,
    PAPER_RANGES,
    REALISTIC_RANGES,
    REALISTIC_STRENGTHS,
    WHOLE_FRAME_EFFECTS,
    resolve_hidden,
)
from synthaug.diagnose.reference_camera.simulate import MeasuredSeed, make_measured_seedset
from synthaug.diagnose.reference_camera.truth import load_truth

__all__ = [
    "REALISTIC_STRENGTHS",
    "REALISTIC_RANGES",
    "OUTSIDE_EFFECTS",
    "PAPER_RANGES",
    "WHOLE_FRAME_EFFECTS",
    "OBJECT_ONLY_EFFECTS",
    "make_measured_seedset",
    "quadcopter_parts",
    "perturb_mesh",
    "resolve_hidden",
    "seed_geometry",
    "load_truth",
    "Nuisances",
    "MeasuredSeed",
    "wb_gains",
    "column_gains",
]
