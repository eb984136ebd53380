"""View cache: exact GL renders over a grid of out-of-plane views, posed in torch.

One pyrender call costs ~4-5 ms here, far too slow for thousands of samples per
second. With an orthographic camera, the pose R = Rz(γ) Ry(β) Rx(α) splits
into a *view* (α, β), which changes what the camera sees, and an in-plane
rigid motion (γ, t_x, t_y), which acts on the image exactly. So we render
coverage and normals once over a fine (α, β) grid (the sprites), and per
sample pick the nearest view and apply γ, t and the object scale by one
batched bilinear warp (``grid_sample``), rotating the normals' xy by γ.

The only approximations are the (α, β) quantisation (at most half a grid
step) and bilinear resampling; :func:`approximation_error` measures both
against exact renders (``benchmarks/bench_render.py`` reports it).

Sprites are cached on disk (``$SYNTHAUG_CACHE`` or ``~/.cache/synthaug``,
folder ``views/``), keyed by the mesh geometry and grid, and memory-mapped, so
DataLoader workers share one copy. One entry is ~100 MB at the defaults (5°
grid, 96 px: 2,664 views × 4 bytes × 96²). The folder is bounded: after each
new entry the least recently used ones are removed until the total is at most
``$SYNTHAUG_CACHE_MAX_MB`` (default 1024 MB; the newest entry is always kept). Building uses :class:`~synthaug.render.server.Renderer`, so the
calling process never holds a GL context (fork-safe).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F

from synthaug._io import read_versioned_json
from synthaug.render.mesh import load_mesh, mesh_fingerprint
from synthaug.render.pose import rotation_matrices

CACHE_VERSION = 1
DEFAULT_CACHE_MAX_MB = 1024


def default_cache_dir() -> Path:
    """``$SYNTHAUG_CACHE``, else ``~/.cache/synthaug``."""
    return Path(os.environ.get("SYNTHAUG_CACHE", Path.home() / ".cache" / "synthaug"))


def cache_limit_bytes() -> int:
    """The bound of the view cache folder: ``$SYNTHAUG_CACHE_MAX_MB`` (default 1024) megabytes."""
    raw = os.environ.get("SYNTHAUG_CACHE_MAX_MB", str(DEFAULT_CACHE_MAX_MB))
    try:
        mb = float(raw)
    except ValueError:
        raise ValueError(f"SYNTHAUG_CACHE_MAX_MB must be a number of megabytes, got {raw!r}") from None
    if not mb >= 0:
        raise ValueError(f"SYNTHAUG_CACHE_MAX_MB must be >= 0, got {raw!r}")
    return int(mb * 2**20)


def _entry_bytes(folder: Path) -> int:
    return sum(f.stat().st_size for f in folder.iterdir() if f.is_file())


def prune_cache(root: str | os.PathLike, max_bytes: int, *, keep: str | os.PathLike | None = None) -> list[Path]:
    """Remove the least recently used view-cache entries under ``root/views`` until they total ``<= max_bytes``.

    "Used" is the mtime of an entry's ``meta.json`` (touched on every load).
    ``keep`` (an entry folder) is never removed. Processes that memory-mapped a
    removed entry keep reading it (POSIX unlink semantics). Returns the removed folders.
    """
    views = Path(root) / "views"
    if not views.is_dir():
        return []
    entries = []
    for d in views.iterdir():
        meta = d / "meta.json"
        if d.is_dir() and not d.name.startswith(".") and meta.exists():
            entries.append((meta.stat().st_mtime, d, _entry_bytes(d)))
    total = sum(b for _, _, b in entries)
    removed = []
    keep_path = None if keep is None else Path(keep).resolve()
    for _, d, size in sorted(entries, key=lambda e: e[0]):
        if total <= max_bytes:
            break
        if keep_path is not None and d.resolve() == keep_path:
            continue
        shutil.rmtree(d, ignore_errors=True)
        total -= size
        removed.append(d)
    return removed


class ViewCache:
    """Sprites of one mesh over an (α, β) grid.

    Build with :meth:`build`; pose with :meth:`layers`.

    Args:
        coverage: (N, S, S) uint8, coverage × 255.
        normals: (N, 3, S, S) int8, camera-frame normals × 127.
        (Held as one (N, 4, S', S'') int8 tensor, coverage requantised to 0..127,
        cropped to the box where some view has content, so a batch is one
        small gather and one conversion.)
        alphas: (Na,) grid of α (rad); betas: (Nb,) grid of β; view n = ia * Nb + ib.
        sprite_scale: mesh unit length as a fraction of the sprite side.
    """

    def __init__(self, coverage: np.ndarray, normals: np.ndarray, alphas: np.ndarray, betas: np.ndarray,
                 sprite_scale: float, fingerprint: str = "") -> None:
        n = len(alphas) * len(betas)
        if coverage.shape[0] != n or normals.shape[0] != n:
            raise ValueError(f"expected {n} sprites for the grid, got {coverage.shape[0]} / {normals.shape[0]}")
        self.coverage = torch.from_numpy(np.asarray(coverage))
        self.normals = torch.from_numpy(np.asarray(normals))
        cov7 = torch.round(self.coverage.to(torch.float32) * (127.0 / 255.0)).to(torch.int8)
        sprites = torch.cat([cov7[:, None], self.normals], dim=1)
        # Only the box where some view has content is kept: outside it every sprite is zero, which is what
        # grid_sample's zero padding reads there, so the crop changes nothing but the bytes gathered per batch.
        filled = torch.zeros(sprites.shape[-2:], dtype=torch.bool)
        for i in range(0, len(sprites), 256):  # in slices: no full-size boolean copy
            filled |= (sprites[i:i + 256] != 0).any(1).any(0)
        rows, cols = torch.nonzero(filled.any(1)).flatten(), torch.nonzero(filled.any(0)).flatten()
        y0, y1 = (int(rows[0]), int(rows[-1]) + 1) if len(rows) else (0, 1)
        x0, x1 = (int(cols[0]), int(cols[-1]) + 1) if len(cols) else (0, 1)
        self._sprites = sprites[..., y0:y1, x0:x1].contiguous()
        self._content_box = (y0, y1, x0, x1)
        self.alphas = np.asarray(alphas, np.float64)
        self.betas = np.asarray(betas, np.float64)
        self.sprite_scale = float(sprite_scale)
        self.sprite_size = int(coverage.shape[-1])
        self.fingerprint = fingerprint

    # ------------------------------------------------------------- building
    @classmethod
    def build(
        cls,
        mesh: Any,
        *,
        step_deg: float = 5.0,
        sprite_size: int = 96,
        sprite_scale: float = 0.5,
        supersample: int = 2,
        cache_dir: str | os.PathLike | None = None,
        renderer: Any = None,
    ) -> "ViewCache":
        """Render (or load from the disk cache) the sprites of ``mesh``.

        Args:
            mesh: path, built-in name or trimesh (normalised on load).
            step_deg: grid step of α and β in degrees (error ≤ step/2 per angle).
            sprite_size: sprite side in pixels; choose ≥ the largest object size
                you will render / sprite_scale * object_scale.
            sprite_scale: mesh unit length as a fraction of the sprite side
                (0.5 leaves room for any rotation of a unit-size mesh).
            supersample: GL renders at ``sprite_size * supersample``, box-averaged.
            cache_dir: where sprites are stored; None = default; ``False``-y
                string "" disables the disk cache.
            renderer: an existing :class:`~synthaug.render.server.Renderer` to use.
        """
        if not 0.1 <= step_deg <= 45:
            raise ValueError(f"step_deg must be in [0.1, 45], got {step_deg}")
        if sprite_size < 8:
            raise ValueError(f"sprite_size must be >= 8, got {sprite_size}")
        if not 0 < sprite_scale <= 1:
            raise ValueError(f"sprite_scale must be in (0, 1], got {sprite_scale}")
        mesh = load_mesh(mesh)
        fp = mesh_fingerprint(mesh)
        na = int(round(360.0 / step_deg))
        nb = int(round(180.0 / step_deg)) + 1
        alphas = -math.pi + 2 * math.pi * np.arange(na) / na
        betas = np.linspace(-math.pi / 2, math.pi / 2, nb)
        key = f"v{CACHE_VERSION}_{fp}_s{step_deg:g}_px{sprite_size}_sc{sprite_scale:g}_ss{supersample}"
        root = default_cache_dir() if cache_dir is None else (Path(cache_dir) if cache_dir != "" else None)
        if root is not None:
            folder = root / "views" / key
            if (folder / "meta.json").exists():
                try:
                    return cls._load(folder)
                except (OSError, ValueError):
                    pass  # corrupt cache entry: rebuild below
        from synthaug.render.server import Renderer

        own = renderer is None
        r = Renderer(mesh) if own else renderer
        try:
            aa, bb = np.meshgrid(alphas, betas, indexing="ij")
            rot = rotation_matrices(aa.ravel(), bb.ravel(), np.zeros(aa.size))
            covs, nrms = [], []
            for i in range(0, len(rot), 256):
                c, n = r.render_views(rot[i:i + 256], None, size=sprite_size, scale=sprite_scale,
                                      supersample=supersample)
                covs.append(c)
                nrms.append(n)
        finally:
            if own:
                r.close()
        cov = np.round(np.concatenate(covs) * 255).astype(np.uint8)
        nrm = np.round(np.concatenate(nrms) * 127).astype(np.int8)
        cache = cls(cov, nrm, alphas, betas, sprite_scale, fp)
        if root is not None:
            cache._save(root / "views" / key)
            prune_cache(root, cache_limit_bytes(), keep=root / "views" / key)
        return cache

    def _save(self, folder: Path) -> None:
        folder.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}."))
        try:
            np.save(tmp / "coverage.npy", self.coverage.numpy())
            np.save(tmp / "normals.npy", self.normals.numpy())
            np.save(tmp / "alphas.npy", self.alphas)
            np.save(tmp / "betas.npy", self.betas)
            (tmp / "meta.json").write_text(json.dumps({"version": CACHE_VERSION, "sprite_scale": self.sprite_scale,
                                                       "fingerprint": self.fingerprint}))
            try:
                os.rename(tmp, folder)
            except OSError:  # another process saved it first
                shutil.rmtree(tmp, ignore_errors=True)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise

    @classmethod
    def _load(cls, folder: Path) -> "ViewCache":
        meta = read_versioned_json(folder / "meta.json", format=None, version=CACHE_VERSION, what="view cache")
        try:
            os.utime(folder / "meta.json")  # "recently used", for prune_cache
        except OSError:
            pass  # a read-only cache is fine
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # torch warns that memory-mapped arrays are read-only
            return cls(np.load(folder / "coverage.npy", mmap_mode="r"), np.load(folder / "normals.npy", mmap_mode="r"),
                       np.load(folder / "alphas.npy"), np.load(folder / "betas.npy"), meta["sprite_scale"],
                       meta["fingerprint"])

    # -------------------------------------------------------------- posing
    @property
    def num_views(self) -> int:
        return int(self.coverage.shape[0])

    def view_index(self, alpha: torch.Tensor, beta: torch.Tensor) -> torch.Tensor:
        """Index of the nearest grid view for each (α, β) (α wraps, β clamps)."""
        a = torch.as_tensor(alpha, dtype=torch.float64)
        b = torch.as_tensor(beta, dtype=torch.float64)
        na, nb = len(self.alphas), len(self.betas)
        ia = torch.round((a + math.pi) / (2 * math.pi) * na).long() % na
        ib = torch.round((b + math.pi / 2) / math.pi * (nb - 1)).long().clamp(0, nb - 1)
        return ia * nb + ib

    def grid_pose(self, alpha: torch.Tensor, beta: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The (α, β) of the grid view that :meth:`layers` uses."""
        idx = self.view_index(alpha, beta)
        nb = len(self.betas)
        return torch.as_tensor(self.alphas)[idx // nb], torch.as_tensor(self.betas)[idx % nb]

    def layers(
        self,
        alpha: torch.Tensor,
        beta: torch.Tensor,
        gamma: torch.Tensor,
        t_x: torch.Tensor,
        t_y: torch.Tensor,
        *,
        size: int | tuple[int, int],
        object_scale: float | torch.Tensor = 0.7,
        dtype: torch.dtype = torch.float32,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Coverage and normals for a batch of poses.

        Args:
            alpha, beta, gamma, t_x, t_y: (B,) pose (see :mod:`synthaug.render.pose`).
            size: output side (or (H, W)); t and object_scale are fractions of the
                output *width*.
            object_scale: mesh unit length as a fraction of the output width,
                scalar or (B,).

        Returns:
            coverage (B, 1, H, W) in [0, 1] and normals (B, 3, H, W), camera frame.
        """
        h, w = (size, size) if isinstance(size, int) else size
        gamma = torch.as_tensor(gamma, dtype=dtype)
        b = gamma.shape[0]
        if b == 0:
            return torch.zeros(0, 1, h, w, dtype=dtype), torch.zeros(0, 3, h, w, dtype=dtype)
        idx = self.view_index(alpha, beta)
        sprites = self._sprites[idx].to(dtype)  # int8 units: coverage 0..127, normals × 127
        tx = torch.as_tensor(t_x, dtype=dtype)
        ty = torch.as_tensor(t_y, dtype=dtype)
        osc = torch.as_tensor(object_scale, dtype=dtype).expand(b)
        k = self.sprite_scale / osc  # sprite-normalised units per output-normalised unit
        c, s = torch.cos(gamma), torch.sin(gamma)
        aspect = h / w  # output normalised y spans h/w of the width
        # sprite = k * M^-1 (p - 2t), p in width units; M^-1 = [[c, -s], [s, c]]
        px_x, px_y = 2 * tx, 2 * ty
        theta = torch.stack([
            torch.stack([k * c, -k * s * aspect, -k * (c * px_x - s * px_y)], 1),
            torch.stack([k * s, k * c * aspect, -k * (s * px_x + c * px_y)], 1),
        ], 1)
        # from the full sprite's normalised coordinates to the cropped one's (grid_sample, align_corners=False:
        # pixel i of n spans [2i/n - 1, 2(i+1)/n - 1]): x' = (x + 1) S / n' - 2 x0 / n' - 1
        y0, y1, x0, x1 = self._content_box
        side = self.sprite_size
        scale = theta.new_tensor([side / (x1 - x0), side / (y1 - y0)])
        shift = theta.new_tensor([(side - 2 * x0) / (x1 - x0) - 1.0, (side - 2 * y0) / (y1 - y0) - 1.0])
        theta = theta * scale[:, None]
        theta = torch.cat([theta[..., :2], theta[..., 2:] + shift[:, None]], -1)
        grid = F.affine_grid(theta, [b, 4, h, w], align_corners=False)
        out = F.grid_sample(sprites, grid, mode="bilinear", padding_mode="zeros", align_corners=False)
        # bilinear sampling is linear: scale to [0, 1] / unit normals after it, on the smaller output
        cov = out[:, :1].mul(1.0 / 127.0).clamp_(0.0, 1.0)
        raw = out[:, 1:]
        # the γ rotation keeps lengths, so normalise with the unrotated length (threshold 1e-3 in unit
        # normals = 0.127 in int8 units)
        sq = torch.addcmul(torch.addcmul(raw[:, 2:] * raw[:, 2:], raw[:, 1:2], raw[:, 1:2]), raw[:, :1], raw[:, :1])
        inv = torch.where(sq > 0.127 ** 2, sq.clamp_min(0.127 ** 2).rsqrt(), 0.0)
        zero, one = torch.zeros_like(c), torch.ones_like(c)
        rot = torch.stack([torch.stack([c, -s, zero], 1), torch.stack([s, c, zero], 1),
                           torch.stack([zero, zero, one], 1)], 1)  # γ about the camera axis, (B, 3, 3)
        nrm = torch.bmm(rot, raw.reshape(b, 3, h * w)).view(b, 3, h, w) * inv
        return cov, nrm


def _layer_agreement(cov_c, nrm_c, cov_e, nrm_e) -> dict[str, float]:
    n = cov_c.shape[0]
    iou = torch.minimum(cov_c, cov_e).sum((1, 2, 3)) / torch.maximum(cov_c, cov_e).sum((1, 2, 3)).clamp_min(1e-6)
    mad = (cov_c - cov_e).abs().mean((1, 2, 3))
    both = (cov_c > 0.5) & (cov_e > 0.5)
    ang = torch.rad2deg(torch.acos((nrm_c * nrm_e).sum(1, keepdim=True).clamp(-1, 1)))
    med_ang = torch.stack([ang[i][both[i]].median() if both[i].any() else torch.tensor(float("nan"))
                           for i in range(n)])
    return {"iou_median": float(iou.median()), "iou_p05": float(iou.quantile(0.05)),
            "coverage_mad_median": float(mad.median()), "normal_angle_deg_median": float(med_ang.nanmedian())}


def approximation_error(cache: ViewCache, renderer: Any, *, n: int = 64, size: int = 64, object_scale: float = 0.7,
                        seed: int = 0) -> dict[str, Any]:
    """Cache vs exact renders at random poses.

    Soft-coverage IoU, mean |Δcoverage| and the median angle between normals
    (medians and 5th percentile over ``n`` poses drawn uniformly: α ∈ [-π, π),
    β ∈ [-π/2, π/2], γ ∈ [-π, π), t ∈ [-0.1, 0.1]). ``random`` is the full error;
    ``grid_aligned`` snaps (α, β) to the grid first, so it isolates the
    resampling part (the rest is view quantisation).
    """
    g = torch.Generator().manual_seed(seed)
    a = (torch.rand(n, generator=g) * 2 - 1) * math.pi
    b = (torch.rand(n, generator=g) - 0.5) * math.pi
    gm = (torch.rand(n, generator=g) * 2 - 1) * math.pi
    tx = (torch.rand(n, generator=g) - 0.5) * 0.2
    ty = (torch.rand(n, generator=g) - 0.5) * 0.2
    out: dict[str, Any] = {"poses": n, "size": size, "object_scale": object_scale,
                           "grid_step_deg": float(np.degrees(cache.alphas[1] - cache.alphas[0])),
                           "sprite_size": cache.sprite_size}
    for name, (aa, bb) in (("random", (a, b)), ("grid_aligned", cache.grid_pose(a, b))):
        aa, bb = aa.float(), bb.float()
        cov_c, nrm_c = cache.layers(aa, bb, gm, tx, ty, size=size, object_scale=object_scale)
        cov_e, nrm_e = renderer.layers(aa, bb, gm, tx, ty, size=size, scale=object_scale)
        out[name] = _layer_agreement(cov_c, nrm_c, cov_e, nrm_e)
    return out
