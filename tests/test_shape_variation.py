"""Shape variation (issue 16's silhouette factor): variants of a coarse mesh, and the dataset drawing one per item."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch
import trimesh

from synthaug import SyntheticObjectDataset
from synthaug.params import CaptureParams
from synthaug.render.mesh import load_mesh, make_quadcopter, mesh_parts, shape_variants

CACHE = {"step_deg": 30, "sprite_size": 48}


def test_parts_are_the_connected_pieces_of_the_builtin_quadcopter():
    """make_quadcopter concatenates a body, a belly box and per arm an arm, a motor, a rotor and a leg; opposite arms
    start at the centre and share their inner corners, so they are one part: 2 + 2 + 3 × 4 = 16."""
    parts = mesh_parts(make_quadcopter())
    assert len(np.unique(parts)) == 16 and (parts >= 0).all()
    # two boxes apart are two parts; touching at their corners, one; a box with its vertices repeated per face is one
    a = trimesh.creation.box(extents=(1, 1, 1))
    apart = trimesh.creation.box(extents=(1, 1, 1), transform=trimesh.transformations.translation_matrix((2, 0, 0)))
    touching = trimesh.creation.box(extents=(1, 1, 1), transform=trimesh.transformations.translation_matrix((1, 0, 0)))
    two = mesh_parts(trimesh.util.concatenate([a, apart]))
    assert len(np.unique(two)) == 2 and len(np.unique(two[:8])) == 1
    assert len(np.unique(mesh_parts(trimesh.util.concatenate([a, touching])))) == 1
    split = trimesh.Trimesh(a.vertices[a.faces.ravel()], np.arange(36).reshape(12, 3), process=False)
    assert len(np.unique(mesh_parts(split))) == 1
    lone = trimesh.Trimesh(np.vstack([a.vertices, [[5, 5, 5]]]), a.faces, process=False)
    assert mesh_parts(lone)[-1] == -1 and (mesh_parts(lone)[:-1] == 0).all()


def _per_axis_affine(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float]:
    """Least squares y[:, d] = a_d x[:, d] + b_d per axis: the slopes and the largest residual."""
    slopes, worst = [], 0.0
    for d in range(3):
        A = np.stack([x[:, d], np.ones(len(x))], 1)
        coef, *_ = np.linalg.lstsq(A, y[:, d], rcond=None)
        slopes.append(coef[0])
        worst = max(worst, float(np.abs(A @ coef - y[:, d]).max()))
    return np.array(slopes), worst


def test_each_variant_stretches_the_axes_and_scales_every_part_about_its_centre():
    s = 0.3
    base = load_mesh("quadcopter")
    vs = shape_variants("quadcopter", 5, strength=s, seed=4)
    assert np.array_equal(vs[0].vertices, base.vertices)
    parts = mesh_parts(base)
    for v in vs[1:]:
        assert np.array_equal(v.faces, base.faces)
        assert v.extents.max() == pytest.approx(1.0) and np.abs(v.bounds.mean(0)).max() < 1e-9
        slopes = []
        for k in np.unique(parts):
            sel = parts == k
            a, worst = _per_axis_affine(base.vertices[sel], v.vertices[sel])
            assert worst < 1e-9  # a part keeps its shape up to per-axis scale and a shift
            slopes.append(a)
        slopes = np.array(slopes)  # (parts, 3) = part factor × axis factor × the normalisation
        # the axis factors are shared by every part: each part's slope ratios between axes are the same
        ratios = slopes / slopes[:, :1]
        assert np.allclose(ratios, ratios[0], rtol=1e-6)
        assert not np.allclose(ratios[0], 1.0)  # and the axes were stretched
        # part factors differ, within (1 + s)^±2 of one another (each in [1/(1+s), 1+s])
        f = slopes[:, 0]
        assert f.max() / f.min() <= (1 + s) ** 2 + 1e-9 and f.max() / f.min() > 1.05
    again = shape_variants("quadcopter", 5, strength=s, seed=4)
    assert all(np.array_equal(a.vertices, b.vertices) for a, b in zip(vs, again))
    other = shape_variants("quadcopter", 5, strength=s, seed=5)
    assert not np.array_equal(vs[1].vertices, other[1].vertices)


def test_bad_variant_arguments_are_refused():
    with pytest.raises(ValueError, match="n must be an integer >= 1"):
        shape_variants("quadcopter", 0)
    with pytest.raises(ValueError, match="strength must be > 0"):
        shape_variants("quadcopter", 3, strength=0.0)


def _dataset(mesh, **kw):
    bgs = [np.full((48, 48), 90 + 30 * i, np.uint8) for i in range(3)]
    params = CaptureParams.sample(3, generator=torch.Generator().manual_seed(2))
    return SyntheticObjectDataset(mesh, bgs, params, length=40, patch_size=32, negative_fraction=0.0,
                                  object_scale=0.7, render=CACHE, seed=7, **kw)


@pytest.mark.slow
def test_dataset_draws_a_shape_per_item_and_renders_it_as_that_mesh_alone():
    plain = _dataset("quadcopter")
    varied = _dataset("quadcopter", shape_variation=0.3, shape_variants=4)
    assert plain.n_shapes == 1 and varied.n_shapes == 4
    ps = [varied.make_params(i) for i in range(len(varied))]
    # the shape is drawn after every other draw: the rest of each item is the plain dataset's
    for i, p in enumerate(ps):
        assert dataclasses.replace(p, variant=0) == plain.make_params(i)
    counts = np.bincount([p.variant for p in ps], minlength=4)
    assert (counts > 0).all()  # 40 draws over 4 shapes
    # an item of shape v is the item a dataset on that variant mesh alone renders with the same draws
    meshes = shape_variants("quadcopter", 4, strength=0.3, seed=7)
    batch = varied.render(ps)  # one batch: the shapes rendered group by group, put back in place
    for v in (1, 3):
        alone = _dataset(meshes[v])
        for k in [k for k, p in enumerate(ps) if p.variant == v][:3]:
            img, _ = alone.render(dataclasses.replace(ps[k], variant=0))
            assert torch.equal(batch[k][0], img)
            assert torch.equal(varied[k][0], img)
    # and the shapes differ: items of shape 0 are the plain dataset's, the others are not
    k0 = next(k for k, p in enumerate(ps) if p.variant == 0)
    k1 = next(k for k, p in enumerate(ps) if p.variant == 1)
    assert torch.equal(batch[k0][0], plain[k0][0])
    assert not torch.equal(batch[k1][0], plain[k1][0])


@pytest.mark.slow
def test_shape_variation_frames_objects_as_seeds_with_their_own_shape():
    """object_box measures each object's box on its own shape: read off the image (the material alone, a black
    object over a constant 0.8 background: coverage = 1 - image / 0.8), every object's longest side is the fraction."""
    fit = CaptureParams.default(3)
    fit = fit.replace(w_d=torch.zeros(fit.w_d.shape))
    bgs = [np.full((48, 48), 0.8, np.float32) for _ in range(3)]
    ds = SyntheticObjectDataset("quadcopter", bgs, fit, render=CACHE, length=60, patch_size=40, negative_fraction=0.0,
                                effects=["material"], object_box=0.6, seed=1, shape_variation=0.3, shape_variants=3)
    sides, variants = [], []
    for i in range(len(ds)):
        cov = 1.0 - ds[i][0][0].numpy() / 0.8
        ys, xs = np.nonzero(cov >= 0.5)
        sides.append(max(ys.max() - ys.min() + 1, xs.max() - xs.min() + 1))
        variants.append(ds.make_params(i).variant)
    sides, variants = np.array(sides), np.array(variants)
    # 0.6 x 40 px whatever the shape, to the pixel the first look measures (on this coarse 30° cache a few
    # objects are off by more, as without shape variation: 7 of 200 there)
    for v in range(3):
        assert np.median(sides[variants == v]) == 24
    assert np.mean(np.abs(sides - 24) <= 1) >= 0.85, sides


def test_bad_shape_variation_is_refused():
    for bad in (-0.1, float("nan"), True, "0.3"):
        with pytest.raises(ValueError, match="shape_variation must be a number >= 0"):
            _dataset("quadcopter", shape_variation=bad)
    for bad in (1, 2.5, True):
        with pytest.raises(ValueError, match="shape_variants must be an integer >= 2"):
            _dataset("quadcopter", shape_variation=0.2, shape_variants=bad)
    from synthaug.render.cache import ViewCache

    cache = ViewCache.build("quadcopter", **CACHE)
    with pytest.raises(ValueError, match="not a prebuilt ViewCache"):
        SyntheticObjectDataset("quadcopter", [np.zeros((48, 48), np.uint8)], length=2, patch_size=32,
                               render=cache, shape_variation=0.2)
    p = dataclasses.replace(_dataset("quadcopter").make_params(0), variant=2)
    with pytest.raises(ValueError, match="variant 2 out of range"):
        _dataset("quadcopter").render(p)
