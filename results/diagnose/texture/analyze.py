"""Numbers of results/diagnose/texture/README.md (fits' structure measures and a nested texture grid).

python results/diagnose/texture/analyze.py > results/diagnose/texture/analysis.json
"""
import json
import sys

import numpy as np
import torch

from synthaug.diagnose.residuals import (load_diagnosis_data, pairwise_distance, pixel_distance, render_with,
                                         structure_measures)
from synthaug.effects.pipeline import sample_fields

torch.set_num_threads(1)
SEEDS, MESH = "data/halmstad/seedsets/drone_100", "../shared/data/meshes/quadcopter.glb"
FITS = {"paper_base_uniform_init": "results/paper/fits/drone_100_hog.json",
        "new_base": "results/diagnose/texture/drone_100_hog_base.json",
        "texture": "results/diagnose/texture/drone_100_hog_texture.json"}
out = {}


def sd_obj(x, obj):
    return float(np.nanmedian([x[i, 0][obj[i]].std().item() if obj[i].sum() > 8 else np.nan for i in range(len(x))]))


def summary(d, syn):
    obj = (d.coverage > 0.5)[:, 0]
    s = structure_measures(d, syn, rng=np.random.default_rng(0))
    hog, pix = pairwise_distance(d, syn), pixel_distance(d.real, syn)
    return {"hog_median": float(np.median(hog)), "hog_mean": float(hog.mean()), "pixel_mean": float(pix.mean()),
            "tone_curve_slope": s["tone_curve"]["value"], "hf_power_real_over_syn": float(np.exp(s["high_frequency"]["value"])),
            "hf_p": s["high_frequency"]["p"], "object_sd_real": sd_obj(d.real, obj), "object_sd_syn": sd_obj(syn, obj)}


data = {}
for name, fit in FITS.items():
    d = load_diagnosis_data(SEEDS, fit, MESH)
    data[name] = d
    out[name] = {"fitted": summary(d, render_with(d))}
    off = {"object_noise": {"sigma_n": 0.0}}
    if "object_texture" in d.theta.effects:
        out[name]["texture_off"] = summary(d, render_with(d, {"object_texture": {"texture_amp": 0.0}}))
        off["object_texture"] = {"texture_amp": 0.0}
    out[name]["noise_off"] = summary(d, render_with(d, {"object_noise": {"sigma_n": 0.0}}))
    out[name]["all_off"] = summary(d, render_with(d, off))
    print(name, json.dumps(out[name]["fitted"]), file=sys.stderr)

# nested: the new base fit's Θ held, + a camera-wide texture (a, ℓ) with σ_n as fitted or 0; the texture
# field is the one the fit would draw for that seed (child of its generator_seed)
d = data["new_base"]
p = d.real.shape[-1]
seeds = [json.loads(open(FITS["new_base"]).read())["rows"][i]["extra"]["generator_seed"] for i in range(len(d))]
d.fields["texture"] = torch.cat([sample_fields(["object_texture"], (1, 1, p, p), torch.Generator().manual_seed(int(s)))["texture"]
                                 for s in seeds])
base = pairwise_distance(d, render_with(d))
grid = []
for sn in ("fitted", 0.0):
    for a in (0.0, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0):
        for ell in (0.3, 0.6, 1.0, 1.5, 2.0, 3.0, 4.0):
            ext = {"object_texture": {"texture_amp": a, "texture_scale": ell}}
            if sn != "fitted":
                ext["object_noise"] = {"sigma_n": sn}
            dd = pairwise_distance(d, render_with(d, ext))
            grid.append({"sigma_n": sn, "a": a, "ell": ell, "hog_mean": float(dd.mean()),
                         "rel_change_mean": float(np.mean(dd / base - 1)), "frac_better": float(np.mean(dd < base))})
            if a == 0.0:
                break
best = {sn: min((g for g in grid if g["sigma_n"] == sn), key=lambda g: g["hog_mean"]) for sn in ("fitted", 0.0)}
# per-seed best over the grid (in-sample, 2 extra parameters per seed) with σ_n as fitted
out["nested_grid_on_new_base"] = {"base_hog_mean": float(base.mean()), "best_camera_wide": best, "grid": grid}
print(json.dumps(out, indent=1))
