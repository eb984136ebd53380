"""compare.py --pixel-wd: each seed's w_d re-solved by pixel least squares at its fitted Θ (the render is affine in
w_d, so two renders give it exactly), written to a new fit file. HOG cannot see the object's contrast sign; pixels can.

    PYTHONPATH=. python results/synthetic/demo_box/resolve.py SEEDSET FIT OUT
"""
import sys, torch, json
from synthaug.params import CaptureParams
def resolve_wd(seeds, fit_path, out_path, mesh="quadcopter"):
    from synthaug.data.fitted import fit_view_cache, fitted_scales
    from synthaug.fit.config import patches_tensor
    from synthaug.fit.objective import FitSpace, RenderObjective
    theta, extra, meta = CaptureParams.load_with_extra(fit_path)
    cache = fit_view_cache(meta, mesh)
    scales = fitted_scales(extra, meta, 0.7)
    wds = []
    for i in range(len(seeds)):
        space = FitSpace.default(channels=theta.channels, effects=theta.effects)
        obj = RenderObjective(patches_tensor(seeds.patches[i:i + 1]), patches_tensor(seeds.backgrounds[i:i + 1]),
                              cache, distance=None, space=space, object_scale=float(scales[i]),
                              noise_seed=int(extra[i].get("generator_seed", 0)))
        r = []
        for w in (0.2, 0.6):
            u = space.from_theta(theta[i].replace(w_d=torch.tensor([w])))
            r.append(obj.render(u))
        slope = (r[1] - r[0]) / 0.4
        num = ((obj.target - r[0]) * slope).sum(); den = (slope * slope).sum().clamp_min(1e-9)
        lo, hi = 0.0, 1.0
        wds.append(float((0.2 + num / den).clamp(0.01, 0.99)))
    old = theta.w_d.clone()
    new = theta.replace(w_d=torch.tensor(wds, dtype=old.dtype).reshape(old.shape))
    new.save(out_path, extra=extra, metadata=meta)
    return old, new.w_d
if __name__ == "__main__":
    from synthaug.data.seedset import SeedSet
    s = SeedSet.load(sys.argv[1]); o, n = resolve_wd(s, sys.argv[2], sys.argv[3])
    print(torch.stack([o.flatten(), n.flatten()], 1)[:12])
