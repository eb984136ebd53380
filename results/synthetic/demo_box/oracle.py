"""compare.py --oracle S: a fit file whose capture parameters are the truth of `synthaug demo --seed S`'s videos
(each seed's video: w_d, motion blur σ_u, σ_v and angle as `RenderedQuadcopter` drew them, blurs scaled from frame to
patch pixels by the seed's crop; σ_n 0, σ_s 0.5 frame px); the fitted pose and scale are kept."""
import json, torch
from synthaug.params import CaptureParams
def write_oracle(fit_path, seedset_dir, demo_seed, out_path, patch=40, keep=()):
    theta, extra, meta = CaptureParams.load_with_extra(fit_path)
    recs = json.load(open(f"{seedset_dir}/seedset.json"))["records"]
    rows = theta.as_dict()
    new = {k: v.clone() for k, v in rows.items()}
    for i, r in enumerate(recs):
        k = int(r["video"][-3:])
        g = torch.Generator().manual_seed(demo_seed * 1000 + k)
        t = CaptureParams.sample(1, generator=g, ranges={"w_d": (0.05, 0.35), "sigma_u": (0.3, 1.5), "sigma_v": (0.0, 0.6)})
        f = patch / float(r["crop"][2])
        vals = {"sigma_u": float(t.sigma_u.flatten()[0]) * f, "sigma_v": float(t.sigma_v.flatten()[0]) * f,
                "alpha_m": float(t.alpha_m.flatten()[0]), "w_d": float(t.w_d.flatten()[0]), "sigma_n": 0.0,
                "sigma_s": 0.5 * f}
        for n, v in vals.items():
            if n in keep: continue
            new[n][i] = v
    CaptureParams(new, channels=theta.channels, effects=theta.effects, validate=False).save(out_path, extra=extra, metadata=meta)
    return out_path
