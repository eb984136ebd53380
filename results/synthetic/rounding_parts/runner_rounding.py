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
  ``seed_geometry``'s ``frame_scale`` = crop side / P, at most :data:`VIEW_FRAME_SCALE`: the pyramid level nearest to
  ``1 / frame_scale`` is 1.0 or above when the levels step by 0.8), float where the pyramid shrinks it; the critic
  scores what training sees.

The cell keys do not know of the change: give each mode a ``--work`` folder of its own.

    PYTHONPATH=. python results/synthetic/rounding_parts/runner_rounding.py MODE synthetic --work data/runs_MODE ...
"""
import math
import sys

import numpy as np
import torch

import synthaug.detectors.video_training as video_training
from synthaug.data.seedset import seed_geometry
from synthaug.detectors.critic import least_synthetic
from synthaug.effects.camera_functional import quantize_levels

MODES = ("critic_float", "positives_float", "distractors_float", "view")
VIEW_FRAME_SCALE = 1 / math.sqrt(0.8)
"""``view`` rounds the seeds whose crop side is at most this many P: the geometric midpoint of pyramid levels 1.0 and
0.8, so a seed is rounded where the level nearest to its object's is 1.0 or larger."""

_draw = video_training.synthetic_positives
_distractors = video_training.distractor_negatives
MODE = ""


def distractor_negatives_float(*args, **draw):
    """``distractor_negatives`` with the rounding left out (``distractors_float``)."""
    if draw.get("quantize"):
        print("rounding_parts distractors_float: the distractors kept in float", flush=True)
    return _distractors(*args, **{**draw, "quantize": False})


def rounded_seeds(seedset) -> np.ndarray:
    """``view``: a bool per seed, True where its object is seen near scale 1 (rounded)."""
    return (seed_geometry(seedset)["frame_scale"].numpy() <= VIEW_FRAME_SCALE + 1e-9)


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
    # view: draw every candidate in float (the same items as the library's draw), round the seeds seen near scale 1,
    # then the critic's quarter as synthetic_positives takes it
    drawn = count if realism_keep == 1 else int(math.ceil(count / realism_keep - 1e-9))
    out, idx = _draw(seedset, mesh, fit_file, drawn, quantize=False, realism_keep=1.0, return_seed_index=True,
                     **common)
    small = rounded_seeds(seedset)
    mask = torch.from_numpy(small[idx])
    out = torch.where(mask[:, None, None, None], quantize_levels(out), out)
    print(f"rounding_parts view: {int(small.sum())} of {len(small)} seeds rounded (crop side <= "
          f"{VIEW_FRAME_SCALE:.3f} P), {float(mask.float().mean()):.2f} of the draws", flush=True)
    if drawn > count:
        keep = least_synthetic(np.asarray(seedset.patches), out, idx, count, seed=seed, selection=realism_selection,
                               features=realism_features)
        out, idx = out[torch.from_numpy(keep)], idx[keep]
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
