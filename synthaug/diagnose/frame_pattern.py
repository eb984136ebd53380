"""Patterns fixed in the frame: a sensor's column (row) gains, the same in every frame the camera makes.

A CMOS read-out gives each column its own amplifier, so real frames carry a fixed column pattern: each
frame column's gain differs by a percent or two, the same in every frame. The renderer draws the object
without it, so the object's pixels miss what the background around it has. On an object of 20-30 px the
residual is far too weak to see it (0.02 x the object's intensity), but the whole frames show it well: the
profile of a frame's mean log intensity across its columns, high-passed (a scene's slow changes removed),
is the pattern plus the scene's own column structure (trees, poles, the horizon). The scene's structure is
not fixed in the frame from one video to the next; the camera's pattern is.

So the statistic is the **cross-video agreement of the high-passed profiles at the same frame column**:
each video's mean profile ``D_v`` (its seeds' frames, the object's crop left out), and

    ρ = Σ_{v<u} <D_v, D_u> / ((V - 1) / 2 · Σ_v |D_v|²)

(the mean cross-video inner product over the mean squared norm: 1 when every video shows the same pattern,
about 0 when they do not). Its null keeps every video's own profile and destroys only the alignment
between videos: each video's profile is shifted circularly by its own random offset
(:func:`fixed_line_pattern`, one-sided permutation test, ``n_perm`` shifts drawn from the given generator).
A pattern fixed in frame rows is the same statistic on the rows' profiles.

Frames of other sizes than the most common one are left out (their columns are other columns); with fewer
than two videos (or two seeds) there is nothing to compare and the measure is not applicable.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

__all__ = ["line_profiles", "fixed_line_pattern", "HIGH_PASS"]

HIGH_PASS = 7  # frame px: the running mean removed from a profile (the scene's slow changes)


def line_profiles(frame: np.ndarray, *, exclude: Sequence[float] | None = None,
                  high_pass: int = HIGH_PASS) -> dict[str, np.ndarray]:
    """A frame's high-passed profiles of mean log intensity: ``"x"`` across its columns (W,), ``"y"`` across
    its rows (H,).

    Args:
        frame: (H, W) or (H, W, C) uint8 or float in [0, 1] (colour: the mean of the channels).
        exclude: ``(x0, y0, side)`` frame px: a square left out of the means (the object's crop).
        high_pass: width (px) of the running mean subtracted from each profile.

    Example:
        >>> f = np.full((40, 60), 100, np.uint8); f[:, 30] = 110  # one brighter column
        >>> p = line_profiles(f)
        >>> int(np.argmax(p["x"])), bool(abs(p["y"]).max() < 1e-12)
        (30, True)
    """
    from scipy.ndimage import uniform_filter1d

    f = np.asarray(frame, np.float64)
    if f.ndim == 3:
        f = f.mean(-1)
    if f.ndim != 2:
        raise ValueError(f"frame must be (H, W) or (H, W, C), got shape {np.shape(frame)}")
    if np.asarray(frame).dtype == np.uint8:
        f = f / 255.0
    log = np.log(np.clip(f, 1.0 / 255.0, None))
    w = np.ones_like(log)
    if exclude is not None:
        x0, y0, side = (float(v) for v in exclude)
        h, wd = log.shape
        xa, xb = int(np.clip(np.floor(x0), 0, wd)), int(np.clip(np.ceil(x0 + side), 0, wd))
        ya, yb = int(np.clip(np.floor(y0), 0, h)), int(np.clip(np.ceil(y0 + side), 0, h))
        w[ya:yb, xa:xb] = 0.0
    out = {}
    for name, axis in (("x", 0), ("y", 1)):
        m = (log * w).sum(axis) / np.maximum(w.sum(axis), 1.0)
        out[name] = m - uniform_filter1d(m, int(high_pass), mode="nearest")
    return out


def fixed_line_pattern(profiles: Sequence[np.ndarray], groups: Sequence[Any], rng: np.random.Generator, *,
                       n_perm: int = 4999) -> dict[str, Any] | None:
    """The cross-video agreement of line profiles at the same frame line, with its permutation test.

    Args:
        profiles: one high-passed profile per seed (:func:`line_profiles`' ``"x"`` or ``"y"``).
        groups: each seed's video (seeds of one video are averaged; a seed without one is its own group).
        rng: generator of the circular shifts.
        n_perm: number of random shift sets of the null.

    Returns:
        None when fewer than two groups share the most common profile length; else ``rho`` (the statistic),
        ``p`` (one-sided: the pattern agrees more than chance alignment), ``pattern`` (the mean profile over
        the groups: the estimated log-gain pattern, high-passed), ``amplitude`` (its standard deviation),
        ``period_px`` / ``peak_ratio`` (the pattern spectrum's strongest period and its power over the
        spectrum's median: a periodic pattern has a high ratio), ``groups``, ``seeds`` and ``length``.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> gain = 0.02 * rng.standard_normal(200)  # a fixed pattern, in every video
        >>> prof = [gain + 0.01 * rng.standard_normal(200) for _ in range(12)]
        >>> out = fixed_line_pattern(prof, [i % 4 for i in range(12)], np.random.default_rng(1), n_perm=999)
        >>> out["rho"] > 0.8, out["p"] < 0.01, out["groups"]
        (True, True, 4)
    """
    lengths = [len(p) for p in profiles]
    if not lengths:
        return None
    size = max(set(lengths), key=lengths.count)
    keep = [i for i, n in enumerate(lengths) if n == size]
    names = [str(groups[i]) if groups[i] is not None else f"seed{i}" for i in keep]
    vids = sorted(set(names))
    if len(vids) < 2:
        return None
    prof = np.stack([np.asarray(profiles[i], np.float64) for i in keep])
    lab = np.asarray(names)
    d = np.stack([prof[lab == v].mean(0) for v in vids])  # (V, L)
    n_v = d.shape[0]
    sq = float((d ** 2).sum())  # a circular shift keeps every profile's norm: only the sum over videos changes
    rho = _agreement(d.sum(0)[None], sq, n_v)[0]
    off = rng.integers(0, size, (int(n_perm), n_v))
    off[:, 0] = 0  # only the videos' relative shifts matter
    null = np.empty(int(n_perm))
    cols = np.arange(size)
    for a in range(0, int(n_perm), 512):  # chunks: memory (chunk, length), not (n_perm, videos, length)
        o = off[a:a + 512]
        total = np.zeros((o.shape[0], size))
        for v in range(n_v):
            total += d[v][(cols[None, :] - o[:, v:v + 1]) % size]
        null[a:a + 512] = _agreement(total, sq, n_v)
    pattern = d.mean(0)
    power = np.abs(np.fft.rfft(pattern - pattern.mean())) ** 2
    freqs = np.fft.rfftfreq(size)
    band = freqs >= 2.0 / size  # periods up to half the frame
    in_band = np.where(band, power, -np.inf)
    # the fundamental: the lowest frequency within half the strongest peak (a comb's harmonics are as strong)
    j = int(np.flatnonzero(in_band >= 0.5 * in_band.max())[0])
    return {"rho": float(rho), "p": float((1 + np.sum(null >= rho)) / (int(n_perm) + 1)), "pattern": pattern,
            "amplitude": float(pattern.std()), "period_px": float(1.0 / freqs[j]),
            "peak_ratio": float(power[j] / max(float(np.median(power[band])), 1e-30)),
            "groups": int(n_v), "seeds": len(keep), "length": int(size)}


def _agreement(total: np.ndarray, sq: float, n_v: int) -> np.ndarray:
    """ρ from the (K, L) sums over the groups' profiles, the groups' summed squared norms ``sq`` and their
    number: the mean cross-group inner product over the mean squared norm."""
    return 0.5 * ((total ** 2).sum(-1) - sq) / max(0.5 * (n_v - 1) * sq, 1e-30)
