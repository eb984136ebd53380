"""The runner with every pyramid level rounded to 8-bit levels (stop 106, issue 16; an experiment, not the library).

A real training positive is a uint8 crop (``crop_patch``: resampled, then rounded); the sliding window reads the frame
through ``sliding.resize_image`` in float, so at any scale but 1 the window's values leave the 8-bit lattice and the
exactly flat pixel pairs the training positives have (≈ 0.6 of them) thin out (0.08–0.49 by the object's size,
``../quantize_scale/``). This wraps the runner with ``resize_image`` rounding its output to 1/255 steps (the level a
camera would store), for detection, mining and the scale-jittered mining frames alike; nothing else changes. Use
another ``--work`` folder: the cell keys do not know of the change.

    PYTHONPATH=. python results/synthetic/pyramid_8bit/runner_8bit.py synthetic --work data/runs_pyr8 ...
"""
import sys

import synthaug.detectors.sliding as sliding
from synthaug.effects.camera_functional import quantize_levels

_resize = sliding.resize_image


def resize_image_8bit(image, scale: float):
    """``sliding.resize_image``, rounded to 8-bit levels (frames in [0, 1]); scale 1 is the frame itself."""
    out = _resize(image, scale)
    if scale == 1.0 or not out.is_floating_point():
        return out
    return quantize_levels(out)


sliding.resize_image = resize_image_8bit

if __name__ == "__main__":
    from synthaug.evaluate.runner import main

    if "--work" not in sys.argv:
        sys.exit("give --work (a folder of its own: the cell keys do not know of the rounding)")
    sys.exit(main(sys.argv[1:]))
