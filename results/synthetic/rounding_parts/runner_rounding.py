"""The runner with AdaBoost's 8-bit rounding of the synthetic positives moved or split (stop 107, issue 16; an
experiment, not the library).

``synthetic_positives(quantize=True, realism_keep < 1)`` rounds every draw to 8 bits, then lets the critic keep the
quarter it finds least synthetic; the distractors are rounded after their fading. The recipe in float (``--quantize
off``) changes all three at once. Each mode below wraps the positives' draw (``video_training.synthetic_positives``)
and changes one thing, the distractors (drawn by ``training_sets.distractor_negatives``) left as the recipe's:

- ``critic_float``: the critic scores the float draws, the quarter it keeps is rounded after (the float recipe's
  positives, on the 8-bit lattice);
- ``positives_float``: the positives in float as the float recipe's (critic on float, kept float); distractors 8-bit;
- ``distractors_float``: the positives as the recipe's (8-bit), the distractors in float (as the float recipe's): the
  complement of ``positives_float`` (this mode wraps ``video_training.distractor_negatives`` instead);
- ``view``: each seed's draws rounded where the pyramid sees that seed's object near scale 1 (its crop's frame scale,
  ``seed_geometry``'s ``frame_scale`` = crop side / P, at most 1/sqrt(0.8): the pyramid level nearest to
  ``1 / frame_scale`` is 1.0 or above when the levels step by 0.8), float where the pyramid shrinks it; the critic
  scores what training sees. Since stop 108 the library's ``quantize="native_scale"``
  (``synthaug.detectors.training_sets.NATIVE_SCALE_MAX``, ``native_scale_seeds``); this mode draws through it (the
  stop-107 version, which rounded here, gave the same patches bit for bit: checked on a generated seed set with
  fitted poses, shapes and the weak-learner critic).

The cell keys do not know of the change: give each mode a ``--work`` folder of its own.

    PYTHONPATH=. python results/synthetic/rounding_parts/runner_rounding.py MODE synthetic --work data/runs_MODE ...
"""
import sys

import synthaug.detectors.video_training as video_training
from synthaug.detectors.training_sets import NATIVE_SCALE_MAX, native_scale_seeds
from synthaug.effects.camera_functional import quantize_levels

MODES = ("critic_float", "positives_float", "distractors_float", "view")

_draw = video_training.synthetic_positives
_distractors = video_training.distractor_negatives
MODE = ""


def distractor_negatives_float(*args, **draw):
    """``distractor_negatives`` with the rounding left out (``distractors_float``)."""
    if draw.get("quantize"):
        print("rounding_parts distractors_float: the distractors kept in float", flush=True)
    return _distractors(*args, **{**draw, "quantize": False})


def synthetic_positives_moved(seedset, mesh, fit_file, count, *, quantize: bool = False, realism_keep: float = 1.0,
                              realism_selection: str = "seed", realism_features: str = "hog", seed: int = 0,
                              return_seed_index: bool = False, **kwargs):
    """``synthetic_positives`` with the rounding changed as :data:`MODE` says (``critic_float``, ``positives_float``,
    ``view``; a plain call where nothing is rounded)."""
    if not quantize:
        return _draw(seedset, mesh, fit_file, count, realism_keep=realism_keep, realism_selection=realism_selection,
                     realism_features=realism_features, seed=seed, return_seed_index=return_seed_index, **kwargs)
    common = dict(realism_selection=realism_selection, realism_features=realism_features, seed=seed, **kwargs)
    if MODE in ("critic_float", "positives_float"):
        print(f"rounding_parts {MODE}: the draws scored in float"
              f"{', the kept ones rounded after' if MODE == 'critic_float' else ', kept in float'}", flush=True)
        out, idx = _draw(seedset, mesh, fit_file, count, quantize=False, realism_keep=realism_keep,
                         return_seed_index=True, **common)
        if MODE == "critic_float":
            out = quantize_levels(out)
        return (out, idx) if return_seed_index else out
    # view: the library's rounding by the seed's frame scale
    out, idx = _draw(seedset, mesh, fit_file, count, quantize="native_scale", realism_keep=realism_keep,
                     return_seed_index=True, **common)
    small = native_scale_seeds(seedset)
    print(f"rounding_parts view: {int(small.sum())} of {len(small)} seeds rounded (crop side <= "
          f"{NATIVE_SCALE_MAX:.3f} P), {float(small[idx].mean()):.2f} of the kept draws", flush=True)
    return (out, idx) if return_seed_index else out


if __name__ == "__main__":
    from synthaug.evaluate.runner import main

    if len(sys.argv) < 2 or sys.argv[1] not in MODES:
        sys.exit(f"usage: runner_rounding.py {{{','.join(MODES)}}} RUNNER-ARGS")
    MODE = sys.argv[1]
    if "--work" not in sys.argv:
        sys.exit("give --work (a folder of its own: the cell keys do not know of the change)")
    if MODE == "distractors_float":
        video_training.distractor_negatives = distractor_negatives_float
    else:
        video_training.synthetic_positives = synthetic_positives_moved
    sys.exit(main(sys.argv[2:]))
