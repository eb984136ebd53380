"""Issue 16 item 2: every single-factor swap measured so far, ranked per detector by paired AP gain (trains nothing).

    PYTHONPATH=. python results/synthetic/factors/rank.py [--out results/synthetic/factors/ranking.md]

Each row of :data:`FACTORS` is one swap measured by an earlier stop: two stored ``ProtocolResult`` files (runner
JSON, paths relative to ``results/synthetic``) trained on the same seed sets, machine and protocol, that differ in that
one factor. ``base`` is what the library did when it was measured (its default then, named in ``change``), ``variant``
the swap. Printed per class and detector, sorted by Δ AP@0.5 (variant − base, best first): the paired Δ at IoU 0.5 and
0.3 with their 95 % CIs (the protocol's bootstrap of the test videos, same training seeds and resamples, the runner's
``paired_difference``), the videos improved, and, where the two distributions were also scored by item 1's measure,
the HOG two-sample accuracy (mean over the stored seed sets, 0.5 = indistinguishable) before and after.

The protocol's CI resamples the test videos with the trained detectors fixed; it does not count how much a detector
moves when its training seed set, fit or synthetic draw changes (stop 64: one refit moved a HOG cell by 0.06). The
column "over seeds" is the other view: the paired t interval of the per-seed differences on all test videos
(``scipy.stats.ttest_rel``; seeds are independent training runs, each with its own seed set and fit), wide with 3 seeds.
The column "seeds and videos" counts both: the same Δ with the training seeds resampled as well as the videos
(``paired_difference(resample_seeds=True)``, the pigeonhole bootstrap; mildly conservative, coarse under 5 seeds).

A row with a positive Δ whose CI excludes 0 is a fix worth having; a negative one says what the base's factor is
worth (the swap loses it). Rows of one detector were measured against different bases (the default moved between
stops), so compare the Δ, not the APs, across rows.
"""
from __future__ import annotations

import argparse
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from scipy.stats import ttest_rel

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import paired_difference

ROOT = Path(__file__).resolve().parents[1]  # results/synthetic


@dataclass(frozen=True)
class Factor:
    """One measured swap. ``base`` / ``variant``: a stored result, or several of one condition (e.g. one per training
    seed), combined. ``gap``: ((file, key), (file, key)) of item 1's gap JSONs (``gap_seed{0,1,2}.json`` in the
    folder ``file``), base then variant; None where the swap was not scored that way."""

    cls: str
    detector: str
    category: str
    change: str
    split: str
    base: str | tuple[str, ...]
    variant: str | tuple[str, ...]
    source: str
    gap: tuple[tuple[str, str], tuple[str, str]] | None = None
    note: str = field(default="")


_H = "drone_v2_ensemble/hog_100/hog_100_seeds_20x_synthetic_hog.json"  # Table 1's HOG row (built-in mesh, 5 seeds)
_HOFF = "drone_v2_effects_off/hog_100/hog_100_seeds_20x_synthetic_hog"
_C = "cnn_finetune/test_ft4/cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json"  # the CNN, every effect
_CS = "cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog"
_NB = "without_boundary_blur_and_motion_blur"
_A = "adaboost_100_seeds_20x_synthetic_drone_100_seed_seed_hog_share_0.25"
_AFP = "adaboost_100_seeds_20x_synthetic_drone_100_seed_seed_hog_fitted_poses_share_0.25.json"
_P = "hog_100_seeds_20x_synthetic_hog_twin_prop_airplane"
_PC = "cnn_100_seeds_20x_synthetic_hog_twin_prop_airplane"
_PA = "adaboost_100_seeds_20x_synthetic_hog_twin_prop_airplane"
_ASH = ("adaboost_100_seeds_20x_synthetic_hog_quadcopter_fitted_poses_at_the_seeds_offsets_share_0.25_shapes_varied_"
        "0.3_8_bit_the_25_least_synthetic_of_4x_drawn_of_each_seed_to_a_weak_learner_critic.json")  # stops 98-102
_ASH_CELLS = ("adaboost_distractors/intel_cal_test/seed0/" + _ASH, "adaboost_distractors/intel_cal_test/seed1/" + _ASH,
              "adaboost_distractors/frame_s101/seed2/" + _ASH)  # the shape cell, training seeds 0-2


def _seeds(template: str, seeds: tuple[int | str, ...] = (0, 1, 2, 3, 4)) -> tuple[str, ...]:
    return tuple(template.format(s=s) for s in seeds)


_GLB = "mesh_factor/hog_glb_seed{s}/hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json"  # this machine's fits
_BI = "mesh_factor/hog_builtin_seed{s}/hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin.json"
_GLB5, _BI5 = _seeds(_GLB), _seeds(_BI)  # seeds 0-4 (stop 64)
_GLB10, _BI10 = _seeds(_GLB, tuple(range(10))), _seeds(_BI, tuple(range(10)))  # seeds 0-9 (stop 65)
_BGS = "hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin"  # stop 67: test seeds 0-4 hog_a, 5-9 hog_b
_BGV = _seeds(f"background/hog_val_{{s}}/{_BGS}.json", ("a", "b", "c", "d"))  # the same on validation, seeds 0-9
_CBG = ("test04", "a", "b")  # the CNN's background cells, seeds 0-4 (stop 69, read back) and 5-9 (stop 67)
_CBGV = ("val04_a", "val04_b", "val_a", "val_b")  # the same on validation, seeds 0-1, 2-4 (stop 69), 5-9 (stop 68)
_FITTED_ROT = "rotation: uniform -> around each seed's fitted rotation (20°)"
_RC = "hog_100_seeds_20x_synthetic_hog"  # stop 82's HOG cells (built-in fits, calibrated), seeds 0-9 in four folders
_PS100, _PS12 = (f"hog_{n}_seeds_20x_synthetic_hog_the_25_least_synthetic_of_4x_drawn" for n in (100, 12))  # stop 83
_AT_SEED_GAP = (("placement/gap", "synthetic_hog"), ("placement/gap", "synthetic_hog_uniform_at_seed_poses"))

FACTORS: tuple[Factor, ...] = (
    # ---- drones, HOG (base: d_HOG fits of the built-in quadcopter, every effect, 20x, uniform poses) ----
    Factor("drone", "hog", "capture effects (Fig. 9)", "object noise: fitted -> left out", "test",
           f"{_HOFF}.json", f"{_HOFF}_without_object_noise.json", "drone_v2_effects_off/"),
    Factor("drone", "hog", "capture effects (Fig. 9)", "motion blur: fitted -> left out", "test",
           f"{_HOFF}.json", f"{_HOFF}_without_motion_blur.json", "drone_v2_effects_off/"),
    Factor("drone", "hog", "capture effects (Fig. 9)", "boundary blur: fitted -> left out", "test",
           f"{_HOFF}.json", f"{_HOFF}_without_boundary_blur.json", "drone_v2_effects_off/"),
    Factor("drone", "hog", "capture effects (Fig. 9)", "material (w_d): fitted -> left out", "test",
           f"{_HOFF}.json", f"{_HOFF}_without_material.json", "drone_v2_effects_off/"),
    Factor("drone", "hog", "capture parameters (Fig. 10)", "Θ: each seed's fit -> uniform between the fitted extremes",
           "test", "drone_v2_capture/hog_100/hog_100_seeds_20x_synthetic_hog.json",
           "drone_v2_capture/hog_100/hog_100_seeds_20x_synthetic_hog_capture_uniform.json", "drone_v2_capture/"),
    Factor("drone", "hog", "number of synthetic samples (Fig. 11)", "20 per seed -> 5 per seed", "test",
           "drone_v2_ratio/hog_100/hog_100_seeds_20x_synthetic_hog.json",
           "drone_v2_ratio/hog_100/hog_100_seeds_5x_synthetic_hog.json", "drone_v2_ratio/"),
    Factor("drone", "hog", "pose distribution", _FITTED_ROT, "test",
           _H, "drone_v2_ensemble/hog_100_fitted_poses/hog_100_seeds_20x_synthetic_hog_fitted_poses.json",
           "drone_v2_ensemble/", (("drone_box/gap", "synthetic_hog"), ("drone_box/gap", "synthetic_hog_fitted_poses"))),
    Factor("drone", "hog", "silhouette (mesh)", "mesh of the fits: built-in quadcopter -> quadcopter.glb", "test",
           _BI10, _GLB10, "mesh_factor/",
           (("mesh_factor/gap_builtin", "synthetic_hog_builtin"), ("placement/gap", "synthetic_hog"))),
    Factor("drone", "hog", "background", "each object on its own seed's background -> on another seed's (built-in "
           "fits)", "test", _seeds(f"background/hog_{{s}}/{_BGS}.json", ("a", "b")),
           _seeds(f"background/hog_{{s}}/{_BGS}_backgrounds_of_other_seeds.json", ("a", "b")), "background/",
           (("background/gap", "synthetic_hog_builtin"),
            ("background/gap", "synthetic_hog_builtin_other_backgrounds"))),
    Factor("drone", "hog", "background", "each object on its own seed's background -> on another seed's (built-in "
           "fits)", "val", _BGV,
           _seeds(f"background/hog_val_{{s}}/{_BGS}_backgrounds_of_other_seeds.json", ("a", "b", "c", "d")),
           "background/"),
    Factor("drone", "hog", "background", "each object on its own seed's background -> on another seed's (12 real "
           "seeds; seeds 0-4 refitted at stop 68)", "test",
           ("hog_12_share/bg12/hog_12_seeds_20x_synthetic_hog.json",
            "ten_seeds/hog_12_seeds5_9/hog_12_seeds_20x_synthetic_hog.json"),
           ("hog_12_share/bg12/hog_12_seeds_20x_synthetic_hog_backgrounds_of_other_seeds.json",
            "background/hog_12_b/hog_12_seeds_20x_synthetic_hog_backgrounds_of_other_seeds.json"), "background/"),
    Factor("drone", "hog", "background", "each object on its own seed's background -> on another seed's (12 real "
           "seeds)", "val", _seeds("hog_12_share/{s}/hog_12_seeds_20x_synthetic_hog.json", ("bg12_val", "bg12_val_b")),
           _seeds("hog_12_share/{s}/hog_12_seeds_20x_synthetic_hog_backgrounds_of_other_seeds.json",
                  ("bg12_val", "bg12_val_b")), "background/"),
    Factor("drone", "hog", "silhouette (mesh)", "mesh of the fits: built-in quadcopter -> quadcopter.glb", "val",
           _BGV,
           _seeds("mesh_factor/hog_glb_val_{s}/hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json", ("a", "b")),
           "mesh_factor/"),
    Factor("drone", "hog", "capture effects (Fig. 9)", "both blurs: fitted -> left out (built-in fits)", "val",
           f"hog_blurs/val/{_BGS}.json", f"hog_blurs/val/{_BGS}_{_NB}.json", "hog_blurs/"),
    # stop 82: the realism critic (every draw -> the quarter of 4x drawn a cross-fitted HOG critic finds least
    # synthetic), ten training seeds, both splits; HOG's default since
    Factor("drone", "hog", "appearance (realism critic)", "every draw -> the quarter of 4x drawn that a critic in HOG "
           "features finds least synthetic (built-in fits, calibrated)", "test",
           _seeds(f"realism_critic/test_{{s}}/{_RC}.json", "abcd"),
           _seeds(f"realism_critic/test_{{s}}/{_RC}_the_25_least_synthetic_of_4x_drawn.json", "abcd"),
           "realism_critic/",
           (("realism_critic/gap", "synthetic_hog"), ("realism_critic/gap", "synthetic_hog_critic_0p25"))),
    Factor("drone", "hog", "appearance (realism critic)", "every draw -> the quarter of 4x drawn that a critic in HOG "
           "features finds least synthetic (built-in fits, calibrated)", "val",
           _seeds(f"realism_critic/val_{{s}}/{_RC}.json", "abcd"),
           _seeds(f"realism_critic/val_{{s}}/{_RC}_the_25_least_synthetic_of_4x_drawn.json", "abcd"),
           "realism_critic/"),
    # stop 83: the critic's quarter taken of each seed's own draws instead of the whole draw, ten training seeds,
    # 100 and 12 seeds, both splits; HOG's default since
    *(Factor("drone", "hog", "appearance (realism critic)", "the critic's quarter of the whole draw -> of each seed's "
             f"own draws{'' if n == 100 else f' ({n} real seeds)'} (built-in fits, calibrated)", sp,
             _seeds(f"realism_critic/per_seed_{n}/{sp}_{{s}}/{stem}.json", tuple(range(10))),
             _seeds(f"realism_critic/per_seed_{n}/{sp}_{{s}}/{stem}_of_each_seed.json", tuple(range(10))),
             "realism_critic/",
             (("realism_critic/gap_per_seed", "synthetic_hog_critic_0p25"),
              ("realism_critic/gap_per_seed", "synthetic_hog_critic_0p25_per_seed")) if (n, sp) == (100, "test")
             else None)
      for n, stem in ((100, _PS100), (12, _PS12)) for sp in ("test", "val")),
    Factor("drone", "hog", "appearance (object noise level)", "σ_n of the built-in fits -> of the .glb fits, seed by "
           "seed (built-in mesh)", "test", _BI5, _seeds("mesh_factor/hog_builtin_gnoise_seed{s}/"
           "hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin_gnoise.json"), "mesh_factor/"),
    Factor("drone", "hog", "appearance (object noise level)", "σ_n of the .glb fits -> of the built-in fits, seed by "
           "seed (.glb mesh)", "test", _GLB5, _seeds("mesh_factor/hog_glb_bnoise_seed{s}/"
           "hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog_glb_bnoise.json"), "mesh_factor/"),
    Factor("drone", "hog", "silhouette (shape variation)", "shape: the mesh alone -> varied ±30 % (8 shapes)", "test",
           "drone_v2_ensemble/hog_100_baselines/hog_100_seeds_20x_synthetic_hog.json",
           "shape_variation/hog_test/hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog_shapes_varied_0.3.json",
           "shape_variation/",
           (("shape_variation/gap", "synthetic_hog"), ("shape_variation/gap", "synthetic_hog_shapes_0p3"))),
    Factor("drone", "hog", "placement", "t_x, t_y: uniform -> each seed's fitted offset (.glb fits)", "test",
           "placement/hog_100/hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json",
           "placement/hog_100/hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog_at_the_seeds_offsets.json",
           "placement/", _AT_SEED_GAP),
    Factor("drone", "hog", "fit distance (Table 2)", "d_HOG -> d_Eucl fits", "test",
           "table2/hog_hog/hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json",
           "table2/hog_eucl/hog_100_seeds_20x_synthetic_drone_100_seed_seed_eucl.json", "table2/"),
    Factor("drone", "hog", "fit distance (Table 2)", "d_HOG -> d_CNN fits", "test",
           "table2/hog_hog/hog_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json",
           "table2/hog_cnn/hog_100_seeds_20x_synthetic_drone_100_seed_seed_cnn.json", "table2/"),
    Factor("drone", "hog", "scale and box convention", "framing: the mesh's scale -> framed at the fit's size "
           "(ridge box map)", "val", "drone_box/val/hog_100_seeds_20x_synthetic_hog.json",
           "drone_box/val/hog_100_seeds_20x_synthetic_hog_framed_as_the_seeds_fit.json", "drone_box/",
           (("drone_box/gap", "synthetic_hog"), ("drone_box/gap", "synthetic_hog_box_fit"))),
    Factor("drone", "hog", "scale and box convention", "framing: the mesh's scale -> framed at the seed's box "
           "(ridge box map)", "val", "drone_box/val/hog_100_seeds_20x_synthetic_hog.json",
           "drone_box/val/hog_100_seeds_20x_synthetic_hog_framed_as_the_seeds_seed.json", "drone_box/",
           (("drone_box/gap", "synthetic_hog"), ("drone_box/gap", "synthetic_hog_box_seed"))),
    # ---- drones, CNN (base: every effect, as Figs. 9-11 were run; then the default without the blurs) ----
    Factor("drone", "cnn", "capture effects (Fig. 9)", "both blurs: fitted -> left out (the default since stop 52)",
           "test", _C, f"cnn_figs/no_blurs/{_CS}_{_NB}.json", "cnn_figs/",
           (("cnn_figs/gap_blurs", "synthetic_hog"),
            ("cnn_figs/gap_blurs", "synthetic_hog_without_boundary_blur_motion_blur"))),
    Factor("drone", "cnn", "capture effects (Fig. 9)", "object noise: fitted -> left out", "test",
           _C, f"cnn_figs/no_object_noise/{_CS}_without_object_noise.json", "cnn_figs/"),
    Factor("drone", "cnn", "capture effects (Fig. 9)", "motion blur: fitted -> left out", "test",
           _C, f"cnn_figs/effects_off_a/{_CS}_without_motion_blur.json", "cnn_figs/"),
    Factor("drone", "cnn", "capture effects (Fig. 9)", "boundary blur: fitted -> left out", "test",
           _C, f"cnn_figs/no_boundary_blur/{_CS}_without_boundary_blur.json", "cnn_figs/"),
    Factor("drone", "cnn", "capture effects (Fig. 9)", "material (w_d): fitted -> left out", "test",
           _C, f"cnn_figs/no_material/{_CS}_without_material.json", "cnn_figs/"),
    Factor("drone", "cnn", "capture parameters (Fig. 10)", "Θ: each seed's fit -> uniform between the fitted extremes",
           "test", _C, f"cnn_figs/capture_uniform/{_CS}_capture_uniform.json", "cnn_figs/"),
    Factor("drone", "cnn", "number of synthetic samples (Fig. 11)", "20 per seed -> 5 per seed", "test",
           _C, "cnn_figs/ratio5/cnn_100_seeds_5x_synthetic_drone_100_seed_seed_hog.json", "cnn_figs/"),
    Factor("drone", "cnn", "how the detector weighs them", "positives by count -> real seeds hold 3/4 of the weight",
           "test", _C, f"cnn_figs/share25/{_CS}_share_0.25.json", "cnn_figs/"),
    Factor("drone", "cnn", "pose distribution", _FITTED_ROT, "test",
           "cnn_finetune/test_baselines/cnn_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json",
           f"cnn_finetune/test_fitted_poses/{_CS}_fitted_poses.json", "cnn_finetune/"),
    Factor("drone", "cnn", "silhouette (shape variation)", "shape: the mesh alone -> varied ±30 % (8 shapes)", "test",
           _C, f"shape_variation/cnn_test/{_CS}_shapes_varied_0.3.json", "shape_variation/"),
    Factor("drone", "cnn", "scale and box convention", "framing: the mesh's scale -> framed at the fit's size", "test",
           _C, f"cnn_object_box/cnn_test/{_CS}_framed_as_the_seeds_fit.json", "cnn_object_box/"),
    Factor("drone", "cnn", "fit distance (Table 2)", "d_HOG -> d_Eucl fits", "test",
           f"table2/cnn_hog/{_CS}.json", "table2/cnn_eucl/cnn_100_seeds_20x_synthetic_drone_100_seed_seed_eucl.json",
           "table2/"),
    Factor("drone", "cnn", "fit distance (Table 2)", "d_HOG -> d_CNN fits", "test",
           f"table2/cnn_hog/{_CS}.json", "table2/cnn_cnn/cnn_100_seeds_20x_synthetic_drone_100_seed_seed_cnn.json",
           "table2/"),
    Factor("drone", "cnn", "background", "each object on its own seed's background -> on another seed's (built-in "
           "fits, blurs left out; the default since stop 69)", "test",
           _seeds(f"background/cnn_{{s}}/{_CS}_builtin_{_NB}.json", _CBG),
           _seeds(f"background/cnn_{{s}}/{_CS}_builtin_{_NB}_backgrounds_of_other_seeds.json", _CBG), "background/"),
    Factor("drone", "cnn", "background", "each object on its own seed's background -> on another seed's (built-in "
           "fits, blurs left out; the default since stop 69)", "val",
           _seeds(f"background/cnn_{{s}}/{_CS}_builtin_{_NB}.json", _CBGV),
           _seeds(f"background/cnn_{{s}}/{_CS}_builtin_{_NB}_backgrounds_of_other_seeds.json", _CBGV), "background/"),
    Factor("drone", "cnn", "silhouette (mesh)", "mesh of the fits: built-in quadcopter -> quadcopter.glb (blurs "
           "left out; seeds 0-2 stop 63's fits, 3-4 stop 64's)", "test",
           (f"mesh_factor/cnn_100_builtin/{_CS}_builtin_{_NB}.json",
            *_seeds(f"mesh_factor/cnn_builtin_seed{{s}}/{_CS}_builtin_{_NB}.json", (3, 4))),
           (f"placement/cnn_100/{_CS}_{_NB}.json", *_seeds(f"mesh_factor/cnn_glb_seed{{s}}/{_CS}_{_NB}.json", (3, 4))),
           "mesh_factor/",
           (("mesh_factor/gap_builtin", "synthetic_hog_builtin"), ("placement/gap", "synthetic_hog"))),
    Factor("drone", "cnn", "placement", "t_x, t_y: uniform -> each seed's fitted offset (.glb fits, blurs left out)",
           "test", f"placement/cnn_100/{_CS}_{_NB}.json", f"placement/cnn_100/{_CS}_at_the_seeds_offsets_{_NB}.json",
           "placement/", _AT_SEED_GAP),
    Factor("drone", "cnn", "appearance (8-bit levels)", "float renders -> rounded to 8 bits (built-in fits, blurs "
           "left out)", "test", f"mesh_factor/cnn_100_builtin_8bit/cnn_100_seeds_20x_synthetic_drone_100_seed_seed_"
           f"hog_builtin_{_NB}.json", f"mesh_factor/cnn_100_builtin_8bit/cnn_100_seeds_20x_synthetic_drone_100_seed_"
           f"seed_hog_builtin_{_NB}_8_bit.json", "mesh_factor/",
           (("placement/gap", "synthetic_hog"), ("placement/gap", "synthetic_hog_8bit"))),
    Factor("drone", "cnn", "appearance (8-bit levels)", "float renders -> rounded to 8 bits (the CNN's defaults: "
           "built-in fits, blurs left out, other seeds' backgrounds)", "test",
           _seeds(f"quantize/cnn_test_{{s}}/{_CS}_builtin_{_NB}_backgrounds_of_other_seeds.json", ("a", "b")),
           _seeds(f"quantize/cnn_test_{{s}}/{_CS}_builtin_{_NB}_8_bit_backgrounds_of_other_seeds.json", ("a", "b")),
           "quantize/"),
    Factor("drone", "cnn", "appearance (8-bit levels)", "float renders -> rounded to 8 bits (the CNN's defaults: "
           "built-in fits, blurs left out, other seeds' backgrounds)", "val",
           _seeds(f"quantize/cnn_val_{{s}}/{_CS}_builtin_{_NB}_backgrounds_of_other_seeds.json", ("a", "b")),
           _seeds(f"quantize/cnn_val_{{s}}/{_CS}_builtin_{_NB}_8_bit_backgrounds_of_other_seeds.json", ("a", "b")),
           "quantize/"),
    Factor("drone", "cnn", "appearance (8-bit levels)", "float renders -> rounded to 8 bits (.glb fits, blurs left "
           "out)", "test", f"placement/cnn_100/{_CS}_{_NB}.json", f"placement/cnn_100/{_CS}_{_NB}_8_bit.json",
           "placement/", (("placement/gap", "synthetic_hog"), ("placement/gap", "synthetic_hog_8bit"))),
    Factor("drone", "cnn", "fit refined by the detector", "Θ fixed -> refitted against the CNN every mining round "
           "(blurs left out)", "test", f"cnn_refit/default_test/{_CS}_{_NB}.json",
           f"cnn_refit/default_test/{_CS}_{_NB}_d_CNN_refit_every_round.json", "cnn_refit/"),
    Factor("drone", "cnn", "capture effects (Fig. 9)", "both blurs: fitted -> left out (the default since stop 52)",
           "val", f"cnn_figs/val_blurs/{_CS}.json", f"cnn_figs/val_blurs/{_CS}_{_NB}.json", "cnn_figs/"),
    Factor("drone", "cnn", "capture effects (Fig. 9)", "motion blur: fitted -> left out", "val",
           f"cnn_figs/val_blurs/{_CS}.json", f"cnn_figs/val_blurs/{_CS}_without_motion_blur.json", "cnn_figs/"),
    Factor("drone", "cnn", "capture effects (Fig. 9)", "boundary blur: fitted -> left out", "val",
           f"cnn_figs/val_blurs/{_CS}.json", f"cnn_figs/val_blurs/{_CS}_without_boundary_blur.json", "cnn_figs/"),
    Factor("drone", "cnn", "fit refined by the detector", "Θ fixed -> refitted against the CNN every mining round "
           "(blurs left out)", "val", f"cnn_refit/default_val/{_CS}_{_NB}.json",
           f"cnn_refit/default_val/{_CS}_{_NB}_d_CNN_refit_every_round.json", "cnn_refit/"),
    Factor("drone", "cnn", "silhouette (shape variation)", "shape: the mesh alone -> varied ±30 % (8 shapes)", "val",
           f"cnn_finetune/val_ft4/{_CS}.json", f"shape_variation/cnn_val/{_CS}_shapes_varied_0.3.json",
           "shape_variation/"),
    Factor("drone", "cnn", "scale and box convention", "framing: the mesh's scale -> framed at the fit's size", "val",
           f"cnn_finetune/val_ft4/{_CS}.json", f"cnn_object_box/cnn_val/{_CS}_framed_as_the_seeds_fit.json",
           "cnn_object_box/"),
    Factor("drone", "cnn", "appearance (8-bit levels)", "float renders -> rounded to 8 bits (.glb fits, blurs left "
           "out)", "val", f"placement/cnn_100_val/{_CS}_{_NB}.json", f"placement/cnn_100_val/{_CS}_{_NB}_8_bit.json",
           "placement/"),
    # ---- drones, AdaBoost (base: share 0.25, real-positive cascade, quadcopter.glb fits, every effect) ----
    Factor("drone", "adaboost", "capture effects (Fig. 9)", "object noise: fitted -> left out", "test",
           f"adaboost_figs/noise_off/{_A}.json", f"adaboost_figs/noise_off/{_A}_without_object_noise.json",
           "adaboost_figs/"),
    Factor("drone", "adaboost", "capture parameters (Fig. 10)", "Θ: each seed's fit -> uniform between the fitted "
           "extremes", "test", f"adaboost_figs/uniform/{_A}.json", f"adaboost_figs/uniform/{_A}_capture_uniform.json",
           "adaboost_figs/"),
    Factor("drone", "adaboost", "number of synthetic samples (Fig. 11)", "20 per seed -> 5 per seed", "test",
           f"adaboost_fig11/r5/{_A}.json",
           "adaboost_fig11/r5/adaboost_100_seeds_5x_synthetic_drone_100_seed_seed_hog_share_0.25.json",
           "adaboost_fig11/"),
    Factor("drone", "adaboost", "appearance (8-bit levels)", "float renders -> rounded to 8 bits", "test",
           f"adaboost_8bit/share_8bit/{_A}.json", f"adaboost_8bit/share_8bit/{_A}_8_bit.json", "adaboost_8bit/",
           (("adaboost_8bit/gap", "synthetic_hog"), ("adaboost_8bit/gap", "synthetic_hog_8bit"))),
    Factor("drone", "adaboost", "appearance (8-bit levels)", "float renders -> rounded to 8 bits", "val",
           f"adaboost_8bit/val/{_A}.json", f"adaboost_8bit/val/{_A}_8_bit.json", "adaboost_8bit/"),
    Factor("drone", "adaboost", "silhouette (mesh)", "mesh of the fits: quadcopter.glb -> built-in quadcopter",
           "test", f"adaboost_fig11/r5/{_A}.json",
           "mesh_factor/ada_100/adaboost_100_seeds_20x_synthetic_drone_100_seed_seed_hog_builtin_share_0.25.json",
           "mesh_factor/", (("placement/gap", "synthetic_hog"), ("mesh_factor/gap_builtin", "synthetic_hog_builtin"))),
    Factor("drone", "adaboost", "how the detector weighs them", "real seeds hold 3/4 of the weight -> by count",
           "test", f"adaboost_100_share/share/{_A}.json",
           "adaboost_100_share/count/adaboost_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json",
           "adaboost_100_share/"),
    Factor("drone", "adaboost", "how the detector weighs them", "soft cascade: from the real positives -> from every "
           "positive", "test", f"adaboost_100_share/share/{_A}.json", f"adaboost_100_share/share_all/{_A}.json",
           "adaboost_100_share/"),
    Factor("drone", "adaboost", "capture effects (Fig. 9)", "both blurs: fitted -> left out (transfer boosting, "
           "every-positive cascade)", "val",
           "adaboost_blurs/val/adaboost_100_seeds_20x_synthetic_drone_100_seed_seed_hog.json",
           f"adaboost_blurs/val/adaboost_100_seeds_20x_synthetic_drone_100_seed_seed_hog_{_NB}.json",
           "adaboost_blurs/"),
    Factor("drone", "adaboost", "background", "each object on its own seed's background -> on another seed's "
           "(stop 64's .glb fits)", "test", f"adaboost_background/test/{_A}.json",
           f"adaboost_background/test/{_A}_backgrounds_of_other_seeds.json", "adaboost_background/",
           (("adaboost_background/gap", "synthetic_hog"),
            ("adaboost_background/gap", "synthetic_hog_other_backgrounds"))),
    Factor("drone", "adaboost", "background", "each object on its own seed's background -> on another seed's "
           "(stop 64's .glb fits)", "val", f"adaboost_background/val/{_A}.json",
           f"adaboost_background/val/{_A}_backgrounds_of_other_seeds.json", "adaboost_background/"),
    Factor("drone", "adaboost", "pose distribution", _FITTED_ROT + " (stop 64's .glb fits)", "test",
           f"adaboost_background/test/{_A}.json", "adaboost_pose/test/" + _AFP, "adaboost_pose/",
           (("adaboost_pose/gap", "synthetic_hog"), ("adaboost_pose/gap", "synthetic_hog_fitted_poses"))),
    Factor("drone", "adaboost", "pose distribution", _FITTED_ROT + " (stop 64's .glb fits)", "val",
           f"adaboost_background/val/{_A}.json", "adaboost_pose/val/" + _AFP, "adaboost_pose/"),
    Factor("drone", "adaboost", "negatives (rendered distractors)", "the shape cell -> + 5x rendered ellipsoids per "
           "real seed as negatives, drawn as the object (calibrated)", "test",
           _ASH_CELLS,
           _seeds("adaboost_distractors/frame_s101/seed{s}/" + _ASH[:-5] + "_5x_rendered_distractors.json", (0, 1, 2)),
           "adaboost_distractors/"),
    Factor("drone", "adaboost", "negatives (rendered distractors)", "the shape cell -> + 5x soft rendered ellipsoids "
           "per real seed as negatives, faint and blurred against their backgrounds (calibrated)", "test",
           _ASH_CELLS,
           _seeds("adaboost_distractors/frame_s102/soft5/seed{s}/" + _ASH[:-5] + "_5x_soft_rendered_distractors.json",
                  (0, 1, 2)),
           "adaboost_distractors/"),
    # ---- airplanes (twin_prop_airplane.glb fits) ----
    Factor("airplane", "hog", "pose distribution", "rotation: uniform -> around each seed's fitted rotation (20°)",
           "test", f"airplane_v2/hog_100_5seeds/{_P}.json", f"airplane_v2/hog_100_5seeds/{_P}_fitted_poses.json",
           "airplane_v2/"),
    Factor("airplane", "hog", "pose distribution", "rotation: uniform -> around each seed's fitted rotation (20°)",
           "val", f"airplane_v2/hog_100_val/{_P}.json", f"airplane_v2/hog_100_val/{_P}_fitted_poses.json",
           "airplane_v2/"),
    Factor("airplane", "hog", "silhouette (mesh)", "mesh: twin_prop_airplane.glb -> jet_airliner.ply", "test",
           f"airplane_v2/hog_100/{_P}.json",
           "airplane_v2/hog_100_jet/hog_100_seeds_20x_synthetic_hog_jet_airliner.json",
           "airplane_v2/"),
    Factor("airplane", "cnn", "capture effects (Fig. 9)", "both blurs: fitted -> left out (the default since stop 52)",
           "test", f"airplane_v2/cnn_100_noblurs/{_PC}.json", f"airplane_v2/cnn_100_noblurs/{_PC}_{_NB}.json",
           "airplane_v2/"),
    Factor("airplane", "cnn", "capture effects (Fig. 9)", "both blurs: fitted -> left out (the default since stop 52)",
           "val", f"airplane_v2/cnn_100_noblurs_val/{_PC}.json", f"airplane_v2/cnn_100_noblurs_val/{_PC}_{_NB}.json",
           "airplane_v2/"),
    Factor("airplane", "cnn", "background", "each object on its own seed's background -> on another seed's (blurs "
           "left out; the CNN's default since stop 69)", "test",
           _seeds(f"airplane_v2/cnn_100_bg{{s}}/{_PC}_{_NB}.json", ("", "_s3", "_s4")),
           _seeds(f"airplane_v2/cnn_100_bg{{s}}/{_PC}_{_NB}_backgrounds_of_other_seeds.json", ("", "_s3", "_s4")),
           "airplane_v2/"),
    Factor("airplane", "cnn", "background", "each object on its own seed's background -> on another seed's (blurs "
           "left out; the CNN's default since stop 69)", "val",
           _seeds(f"airplane_v2/cnn_100_bg_val{{s}}/{_PC}_{_NB}.json", ("_a", "_s3", "_s4")),
           _seeds(f"airplane_v2/cnn_100_bg_val{{s}}/{_PC}_{_NB}_backgrounds_of_other_seeds.json", ("_a", "_s3", "_s4")),
           "airplane_v2/"),
    Factor("airplane", "cnn", "pose distribution", "rotation: uniform -> around each seed's fitted rotation (20°)",
           "val", f"airplane_v2/cnn_100_val/{_PC}.json", f"airplane_v2/cnn_100_val/{_PC}_fitted_poses.json",
           "airplane_v2/"),
    Factor("airplane", "adaboost", "pose distribution", "rotation: uniform -> around each seed's fitted rotation "
           "(20°; transfer boosting)", "val", f"airplane_v2/adaboost_100_val/{_PA}.json",
           f"airplane_v2/adaboost_100_val/{_PA}_fitted_poses.json", "airplane_v2/"),
)


def _load(paths: str | tuple[str, ...]) -> ProtocolResult:
    parts = (paths,) if isinstance(paths, str) else paths
    return ProtocolResult.combine([ProtocolResult.load(ROOT / p) for p in parts])


def _gap_accuracy(folder: str, key: str) -> float:
    """Mean HOG two-sample accuracy of comparison ``key`` over the folder's stored seed sets."""
    files = sorted((ROOT / folder).glob("gap_seed*.json"))
    if not files:
        raise FileNotFoundError(f"no gap_seed*.json in {ROOT / folder}")
    acc = [json.loads(f.read_text())["comparisons"][key]["families"]["hog"]["two_sample"]["accuracy"] for f in files]
    return float(np.mean(acc))


@dataclass(frozen=True)
class Row:
    factor: Factor
    seeds: tuple[int, ...]
    ap_base: float
    ap_variant: float
    d50: tuple[float, float, float]
    d30: tuple[float, float, float]
    wins: str
    gap: tuple[float, float] | None
    over_seeds: tuple[float, float, float]
    crossed: tuple[float, float, float]


def measure(f: Factor) -> Row:
    """The paired AP difference variant − base of one factor, on the seeds both files hold."""
    base, var = _load(f.base), _load(f.variant)
    if base.protocol.fingerprint() != var.protocol.fingerprint() or base.stems != var.stems or base.split != var.split:
        raise ValueError(f"{f.change}: base and variant were not scored on the same protocol, split and videos")
    if base.split != f.split:
        raise ValueError(f"{f.change}: the files hold split {base.split!r}, the manifest says {f.split!r}")
    seeds = tuple(s for s in base.seed_ids if s in set(var.seed_ids))
    boot = base.protocol.bootstrap
    kw = dict(resamples=boot.resamples, seed=boot.seed, ci=boot.ci, stems=base.stems)
    d = {iou: paired_difference(base.pools(iou), var.pools(iou), **kw) for iou in (0.5, 0.3)}
    crossed = paired_difference(base.pools(0.5), var.pools(0.5), resample_seeds=True, **kw)
    w = d[0.5].wins
    gap = None if f.gap is None else (_gap_accuracy(*f.gap[0]), _gap_accuracy(*f.gap[1]))
    tri = lambda x: (x.difference.estimate, x.difference.low, x.difference.high)  # noqa: E731
    wins = f"{w.improved}/{w.improved + w.worse + w.tied}"
    per_seed = [r.per_seed_ap(0.5) for r in (base, var)]  # every seed's AP, computed once per result
    ap_base, ap_var = (np.array([p[s] for s in seeds]) for p in per_seed)
    ci = ttest_rel(ap_var, ap_base).confidence_interval(0.95)
    return Row(f, seeds, float(ap_base.mean()), float(ap_var.mean()), tri(d[0.5]), tri(d[0.3]), wins, gap,
               (float(np.mean(ap_var - ap_base)), float(ci.low), float(ci.high)), tri(crossed))


def _d(x: tuple[float, float, float]) -> str:
    s = f"{x[0]:+.3f} [{x[1]:+.3f}, {x[2]:+.3f}]"
    return f"**{s}**" if x[1] > 0 or x[2] < 0 else s


def table(rows: list[Row]) -> str:
    """Markdown: one section per class and detector, rows by split then Δ AP@0.5, best first."""
    out: list[str] = []
    for cls in dict.fromkeys(r.factor.cls for r in rows):
        for det in dict.fromkeys(r.factor.detector for r in rows if r.factor.cls == cls):
            sel = [r for r in rows if r.factor.cls == cls and r.factor.detector == det]
            sel.sort(key=lambda r: (r.factor.split != "test", -r.d50[0]))
            out += [f"### {cls}, {det}", "",
                    "| rank | split | factor | swap (base -> variant) | seeds | AP@0.5 base -> variant | "
                    "Δ AP@0.5 [95 % CI] | over seeds [t CI] | seeds and videos [CI] | Δ AP@0.3 [CI] | videos up | "
                    "HOG two-sample, base -> variant | source |",
                    "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
            rank: dict[str, int] = {}
            for r in sel:
                rank[r.factor.split] = rank.get(r.factor.split, 0) + 1
                gap = "–" if r.gap is None else f"{r.gap[0]:.3f} -> {r.gap[1]:.3f} ({r.gap[1] - r.gap[0]:+.3f})"
                out.append(f"| {rank[r.factor.split]} | {r.factor.split} | {r.factor.category} | {r.factor.change} | "
                           f"{len(r.seeds)} | {r.ap_base:.3f} -> {r.ap_variant:.3f} | {_d(r.d50)} | "
                           f"{_d(r.over_seeds)} | {_d(r.crossed)} | {_d(r.d30)} | {r.wins} | {gap} | "
                           f"`{r.factor.source}` |")
            out.append("")
    out.append("Bold: the 95 % CI excludes 0. Δ = variant − base, paired by training seed and test-video resample "
               "(2,000 resamples, the protocol's). Over seeds: the mean per-seed Δ on all test videos and its paired "
               "t interval (training randomness; test videos fixed). Seeds and videos: the Δ's interval with the "
               "training seeds resampled as well as the videos (both counted). Each row's base is named in its "
               "swap; ranks are within a split.")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="write the markdown here too")
    a = ap.parse_args()
    text = table([measure(f) for f in FACTORS])
    print(text)
    if a.out:
        Path(a.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
