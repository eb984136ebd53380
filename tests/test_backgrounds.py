"""Background estimation against known truth (generated panning video) and hand-computed fills."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from synthaug.data.backgrounds import (
    FrameAligner,
    estimate_background,
    estimate_background_single,
    grow_boxes,
    inpaint_region,
    object_mask,
)
from synthaug.data.synthvideo import make_panning_video
from synthaug.data.video import read_video_with_labels


@pytest.fixture(scope="module")
def textured(tmp_path_factory):
    v = make_panning_video(tmp_path_factory.mktemp("tex"), n_frames=70, size=(320, 256), seed=3)
    frames, labels, _ = read_video_with_labels(v.video_path, v.labels_path)
    return v, frames, labels.boxes


@pytest.fixture(scope="module")
def flat(tmp_path_factory):
    v = make_panning_video(tmp_path_factory.mktemp("flat"), n_frames=50, size=(320, 256), seed=4, texture="flat")
    frames, labels, _ = read_video_with_labels(v.video_path, v.labels_path)
    return v, frames, labels.boxes


def _box_err(img, truth, box):
    m = object_mask(img.shape, box, margin_fraction=0, min_margin=0)
    return float(np.mean(np.abs(img[m].astype(float) - truth[m])))


@pytest.mark.parametrize("index", [5, 25, 45, 64])
def test_median_background_matches_truth(textured, index):
    v, frames, boxes = textured
    res = estimate_background(frames, boxes, index)
    assert res.method in ("median", "median+inpaint")
    assert res.n_aligned >= 2
    err = _box_err(res.background, v.backgrounds[index], boxes[index])
    obj = _box_err(v.frames[index], v.backgrounds[index], boxes[index])
    # the object is gone: the fill is close to the true background, far from the object
    assert obj > 15, obj
    assert err < 3.5, err
    assert err < 0.15 * obj
    # outside the object region the background is the frame itself
    assert np.array_equal(res.background[~res.region], frames[index][~res.region])
    # the quality figure is an honest error estimate (same order as the true error)
    assert res.quality < 4


def test_aligner_matches_true_homography(textured):
    v, frames, boxes = textured
    homs = np.load(v.truth_path)["homographies"]  # panorama -> frame t
    al = FrameAligner(frames, boxes)
    pts = np.float32([[20, 20], [300, 30], [160, 128], [40, 230], [290, 240]])[:, None]
    for j, i in [(10, 0), (0, 30), (50, 20)]:
        H = al.homography(j, i)
        assert H is not None
        true = homs[i] @ np.linalg.inv(homs[j])
        err = np.linalg.norm(cv2.perspectiveTransform(pts, H) - cv2.perspectiveTransform(pts, true), axis=-1)
        assert err.max() < 1.5 and err.mean() < 0.6, err


def test_textureless_sky_falls_back_to_inpainting(flat):
    v, frames, boxes = flat
    res = estimate_background(frames, boxes, 20)
    assert res.method == "inpaint"
    assert res.inpainted_fraction == 1.0
    err = _box_err(res.background, v.backgrounds[20], boxes[20])
    assert err < 3.0, err  # a smooth sky is filled well
    assert _box_err(v.frames[20], v.backgrounds[20], boxes[20]) > 30


def test_neighbours_without_box_are_not_used(textured):
    v, frames, boxes = textured
    only_target = [b if i == 30 else None for i, b in enumerate(boxes)]
    res = estimate_background(frames, only_target, 30)
    assert res.method == "inpaint" and res.n_tried == 0


def test_pushpull_is_exact_on_a_linear_ramp():
    yy, xx = np.mgrid[0:60, 0:80]
    img = (40 + 1.5 * xx + 0.8 * yy).astype(np.uint8)  # harmonic, so the membrane fill is the ramp itself
    hole = np.zeros(img.shape, bool)
    hole[20:40, 25:55] = True
    out = inpaint_region(img, hole)
    assert np.abs(out.astype(int) - img).max() <= 2
    assert np.array_equal(out[~hole], img[~hole])


@pytest.mark.parametrize("method", ["telea", "ns"])
def test_opencv_inpainting_methods(method):
    img = np.full((50, 50), 100, np.uint8)
    img[20:30, 20:30] = 0
    out = estimate_background_single(img, [[20, 20, 10, 10]], inpaint_method=method).background
    assert np.abs(out.astype(int) - 100).max() <= 3


def test_single_image_removes_every_box():
    img = np.full((80, 100), 150, np.uint8)
    img[10:20, 10:20] = 0
    img[50:60, 70:80] = 255
    res = estimate_background_single(img, [[10, 10, 10, 10], [70, 50, 10, 10]])
    assert res.method == "inpaint"
    assert np.abs(res.background.astype(int) - 150).max() <= 1


def test_no_box_gives_the_frame():
    img = np.arange(100, dtype=np.uint8).reshape(10, 10)
    res = estimate_background_single(img, None)
    assert res.method == "none" and np.array_equal(res.background, img)


def test_grow_boxes_and_mask():
    assert grow_boxes([[10, 10, 40, 20]], margin_fraction=0.25, min_margin=4).tolist() == [[0.0, 0.0, 60.0, 40.0]]
    assert grow_boxes([[10, 10, 4, 4]], margin_fraction=0.25, min_margin=4).tolist() == [[6.0, 6.0, 12.0, 12.0]]
    m = object_mask((20, 20), [[2.5, 3.5, 4, 4]], margin_fraction=0, min_margin=0)
    assert m.sum() == 5 * 5 and m[3, 2] and m[7, 6] and not m[8, 6]


@pytest.mark.parametrize("kwargs, match", [
    (dict(index=99), "index must be in"),
    (dict(min_samples=0), "min_samples"),
])
def test_bad_arguments(textured, kwargs, match):
    _, frames, boxes = textured
    args = dict(index=0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        estimate_background(frames, boxes, **args)


def test_bad_boxes_and_frames():
    with pytest.raises(ValueError, match="positive size"):
        grow_boxes([[0, 0, -1, 5]])
    with pytest.raises(ValueError, match="uint8"):
        estimate_background(np.zeros((2, 8, 8), np.float32), [None, None], 0)
    with pytest.raises(ValueError, match="one box entry per frame"):
        estimate_background(np.zeros((2, 8, 8), np.uint8), [None], 0)
    with pytest.raises(ValueError, match="inpaint method"):
        inpaint_region(np.zeros((8, 8), np.uint8), np.ones((8, 8), bool), method="magic")


def test_colour_frames_must_match_the_gray_frames():
    frames = np.zeros((3, 20, 30), np.uint8)
    with pytest.raises(ValueError, match="colour_frames must be uint8"):
        estimate_background(frames, [None, [5, 5, 4, 4], None], 1, colour_frames=np.zeros((3, 20, 30), np.uint8))
