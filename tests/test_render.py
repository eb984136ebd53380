"""Mesh loading, exact GL layers, and the view cache against exact renders."""

import math
import struct

import os

import numpy as np
import pytest
import torch
import trimesh

from synthaug.render.cache import ViewCache, approximation_error
from synthaug.render.mesh import load_mesh, make_quadcopter
from synthaug.render.server import Renderer

pytestmark = pytest.mark.gl


@pytest.fixture(scope="module")
def cube_renderer():
    with Renderer(trimesh.creation.box(extents=(1.0, 1.0, 1.0))) as r:
        yield r


@pytest.fixture(scope="module")
def quad_renderer():
    with Renderer("quadcopter") as r:
        yield r


def _centroid(cov):
    m = cov[:, 0]
    ys = torch.arange(m.shape[1], dtype=m.dtype)[:, None]
    xs = torch.arange(m.shape[2], dtype=m.dtype)[None, :]
    s = m.sum((1, 2))
    return torch.stack([(m * xs).sum((1, 2)) / s, (m * ys).sum((1, 2)) / s], 1)


def test_cube_face_on_area_and_normals(cube_renderer):
    # unit cube, scale 0.5 of a 32 px patch: a 16x16 px square, normals toward the camera
    cov, nrm = cube_renderer.layers([0.0], [0.0], [0.0], [0.0], [0.0], size=32, scale=0.5)
    assert cov.shape == (1, 1, 32, 32) and nrm.shape == (1, 3, 32, 32)
    assert float(cov.sum()) == pytest.approx(256.0, abs=1.0)
    inside = cov[0, 0] > 0.99
    assert inside.sum() >= 14 * 14
    np.testing.assert_allclose(nrm[0, :, inside].mean(1).numpy(), [0, 0, 1], atol=0.01)


def test_cube_rotated_about_y_shows_two_faces_with_correct_normals(cube_renderer):
    beta = math.radians(30)
    cov, nrm = cube_renderer.layers([0.0], [beta], [0.0], [0.0], [0.0], size=64, scale=0.4)
    n = nrm[0][:, cov[0, 0] > 0.99].T.numpy()
    front = np.array([math.sin(beta), 0, math.cos(beta)])     # +z face turned by Ry(30°)
    side = np.array([-math.cos(beta), 0, math.sin(beta)])     # -x face turned toward the camera
    close_front = (np.abs(n - front).max(1) < 0.03).mean()
    close_side = (np.abs(n - side).max(1) < 0.03).mean()
    assert close_front > 0.5 and close_side > 0.1 and close_front + close_side > 0.9  # the rest: pixels on the shared edge
    # projected width: cos30 + sin30 (two faces), height 1 -> area fraction of the patch
    area = float(cov.sum()) / (64 * 0.4) ** 2
    assert area == pytest.approx(math.cos(beta) + math.sin(beta), rel=0.03)


def test_translation_and_inplane_rotation_directions(quad_renderer):
    cov, _ = quad_renderer.layers([0.3] * 3, [0.4] * 3, [0.0] * 3, [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], size=50)
    c = _centroid(cov)
    assert float(c[1, 0] - c[0, 0]) == pytest.approx(5.0, abs=0.1)  # t_x > 0 moves right
    assert float(c[2, 1] - c[0, 1]) == pytest.approx(5.0, abs=0.1)  # t_y > 0 moves down


def test_exact_gamma_is_an_image_rotation(cube_renderer):
    # a thin bar along x: γ = +90° must turn it counter-clockwise in the image (vertical)
    with Renderer(trimesh.creation.box(extents=(1.0, 0.1, 0.1))) as r:
        cov, _ = r.layers([0.0, 0.0], [0.0, 0.0], [0.0, math.pi / 2], [0.2, 0.2], [0.0, 0.0], size=40, scale=0.5)
    c = _centroid(cov)
    # t_x = 0.2 is applied after the rotation: centroid stays 8 px right of centre in both
    assert c[:, 0].tolist() == pytest.approx([27.5, 27.5], abs=0.2)  # centre 19.5 + 0.2 * 40
    rows = (cov[1, 0] > 0.5).any(1).sum().item()
    cols = (cov[1, 0] > 0.5).any(0).sum().item()
    assert rows >= 18 and cols <= 4


def test_cache_matches_exact_render_at_grid_views(quad_renderer, small_cache):
    g = torch.Generator().manual_seed(0)
    a = (torch.rand(6, generator=g) * 2 - 1) * math.pi
    b = (torch.rand(6, generator=g) - 0.5) * math.pi
    a, b = small_cache.grid_pose(a, b)  # on the grid: only the in-plane warp is approximated
    gm = (torch.rand(6, generator=g) * 2 - 1) * math.pi
    tx = (torch.rand(6, generator=g) - 0.5) * 0.2
    ty = (torch.rand(6, generator=g) - 0.5) * 0.2
    cc, nc = small_cache.layers(a, b, gm, tx, ty, size=40, object_scale=0.7)
    ce, ne = quad_renderer.layers(a, b, gm, tx, ty, size=40, scale=0.7)
    assert (_centroid(cc) - _centroid(ce)).abs().max() < 0.5  # < half a sprite pixel (48 px sprites)
    torch.testing.assert_close(cc.sum((1, 2, 3)), ce.sum((1, 2, 3)), rtol=0.06, atol=0)
    both = (cc > 0.7) & (ce > 0.7)
    cos = (nc * ne).sum(1, keepdim=True)[both]
    assert cos.median() > 0.97


def test_approximation_error_report(quad_renderer, small_cache):
    err = approximation_error(small_cache, quad_renderer, n=8, size=40)
    assert 0 < err["random"]["iou_median"] <= err["grid_aligned"]["iou_median"] <= 1
    assert err["grid_step_deg"] == pytest.approx(30)


def test_cache_round_trips_through_disk(tmp_path):
    a = ViewCache.build("quadcopter", step_deg=45, sprite_size=16, cache_dir=tmp_path)
    b = ViewCache.build("quadcopter", step_deg=45, sprite_size=16, cache_dir=tmp_path)  # loaded, memory-mapped
    assert torch.equal(a.coverage, b.coverage) and torch.equal(a.normals, b.normals)
    assert len(list((tmp_path / "views").iterdir())) == 1


@pytest.mark.slow
def test_cache_folder_is_bounded_least_recently_used_first(tmp_path, monkeypatch):
    from synthaug.render.cache import prune_cache

    monkeypatch.setenv("SYNTHAUG_CACHE_MAX_MB", "100")
    ViewCache.build("quadcopter", step_deg=45, sprite_size=16, cache_dir=tmp_path)
    ViewCache.build("quadcopter", step_deg=45, sprite_size=20, cache_dir=tmp_path)
    entries = sorted((tmp_path / "views").iterdir())
    sizes = {d.name: sum(f.stat().st_size for f in d.iterdir()) for d in entries}
    assert len(entries) == 2  # both fit in 100 MB
    old, new = sorted(entries, key=lambda d: (d / "meta.json").stat().st_mtime)
    # loading the older entry makes it the most recently used: the other one goes first
    os.utime(old / "meta.json", (1, 1))
    os.utime(new / "meta.json", (2, 2))
    ViewCache.build("quadcopter", step_deg=45, sprite_size=16, cache_dir=tmp_path)  # a load touches it
    limit = max(sizes.values())
    assert prune_cache(tmp_path, limit) == [tmp_path / "views" / [n for n in sizes if "px20" in n][0]]
    assert [d.name for d in (tmp_path / "views").iterdir()] == [n for n in sizes if "px16" in n]
    assert prune_cache(tmp_path, 0, keep=tmp_path / "views" / [n for n in sizes if "px16" in n][0]) == []
    monkeypatch.setenv("SYNTHAUG_CACHE_MAX_MB", "0")  # a new entry is kept, every older one removed
    ViewCache.build("quadcopter", step_deg=45, sprite_size=24, cache_dir=tmp_path)
    assert [d.name for d in (tmp_path / "views").iterdir()][0].endswith("px24_sc0.5_ss2")
    assert len(list((tmp_path / "views").iterdir())) == 1
    monkeypatch.setenv("SYNTHAUG_CACHE_MAX_MB", "lots")
    with pytest.raises(ValueError, match="SYNTHAUG_CACHE_MAX_MB must be a number"):
        ViewCache.build("quadcopter", step_deg=45, sprite_size=28, cache_dir=tmp_path)


def test_builtin_quadcopter_is_unit_size_and_coarse():
    m = make_quadcopter()
    assert m.extents.max() == pytest.approx(1.0)
    assert 100 < len(m.faces) < 5000


@pytest.mark.parametrize("name", ["quadcopter.glb", "twin_prop_airplane.glb", "jet_airliner.ply"])
def test_shared_meshes_load_centred_unit_size(shared_data, name):
    m = load_mesh(shared_data / "meshes" / name)
    assert m.extents.max() == pytest.approx(1.0)
    np.testing.assert_allclose(m.bounds.mean(0), 0, atol=1e-9)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".stl", ".glb"])
def test_formats_round_trip(tmp_path, suffix):
    path = tmp_path / f"box{suffix}"
    trimesh.creation.box(extents=(2.0, 1.0, 0.5)).export(path)
    m = load_mesh(path)
    np.testing.assert_allclose(sorted(m.extents), [0.25, 0.5, 1.0], atol=1e-6)


def test_bad_mesh_files_give_clear_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="mesh file not found: .*nope.obj"):
        load_mesh(tmp_path / "nope.obj")
    empty = tmp_path / "empty.obj"
    empty.write_text("")
    with pytest.raises(ValueError, match="empty.obj"):
        load_mesh(empty)
    corrupt = tmp_path / "corrupt.glb"
    corrupt.write_bytes(b"glTF" + struct.pack("<II", 2, 999) + b"\x00garbage")
    with pytest.raises(ValueError, match="corrupt.glb"):
        load_mesh(corrupt)
    points = tmp_path / "points.ply"
    trimesh.PointCloud(np.random.default_rng(0).random((10, 3))).export(points)
    with pytest.raises(ValueError, match="points.ply"):
        load_mesh(points)
    with pytest.raises(ValueError, match="directory"):
        load_mesh(tmp_path)


def test_renders_a_shared_mesh(shared_data):
    with Renderer(shared_data / "meshes" / "twin_prop_airplane.glb") as r:
        cov, nrm = r.layers([0.0], [math.pi / 2], [0.0], [0.0], [0.0], size=40)
    assert 30 < float(cov.sum()) < 0.9 * 1600
    assert float((nrm.norm(dim=1)[cov[:, 0] > 0.99] - 1).abs().max()) < 0.02


def test_a_worker_that_dies_at_start_says_why(tmp_path, monkeypatch):
    """The worker's exit code and its own log reach the error (else a crash at start reads only "closed its output")."""
    import synthaug.render.server as server
    from synthaug.render.server import RenderError

    fake = tmp_path / "python"
    fake.write_text("#!/bin/sh\necho 'libEGL warning: no usable device (a stand-in GL stack)' >&2\nexit 3\n")
    fake.chmod(0o755)
    monkeypatch.setattr(server.sys, "executable", str(fake))
    r = Renderer("quadcopter", platform="egl")
    with pytest.raises(RenderError, match=r"(?s)exit code 3.*no usable device"):
        r.layers([0.0], [0.0], [0.0], [0.0], [0.0], size=8)
    assert r._proc is None  # nothing left running
