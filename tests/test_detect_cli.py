"""`synthaug detect` and `synthaug evaluate` end to end on a generated video, and a smoke run on real data."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from synthaug.cli import main as cli_main
from synthaug.detectors.base import save_detector
from synthaug.detectors.hog_dpm import HOGDetector

from test_hog_detector import _background, _paint_object, _problem

cv2 = pytest.importorskip("cv2")

N_FRAMES = 6
SIZE = 28.0


def _centre(i: int) -> tuple[float, float]:
    return 50.0 + 15.0 * i, 60.0 + 8.0 * i


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("detect")
    pos, neg = _problem(seed=0, n_pos=60, n_neg=200)
    det = HOGDetector.fit(pos, neg, components=2, mining_rounds=1, generator=torch.Generator().manual_seed(0))
    det.box_in_window = (6.0, 6.0, 28.0, 28.0)
    ckpt = save_detector(det, root / "hog.pt")

    video = root / "V_TOY_001.mp4"
    frames_dir = root / "frames"
    frames_dir.mkdir()
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"mp4v"), 10, (200, 160), True)
    boxes = []
    for i in range(N_FRAMES):
        frame = _background(160, 200, torch.Generator().manual_seed(50 + i))
        if i == 3:
            boxes.append(None)  # object not visible in this frame
        else:
            cx, cy = _centre(i)
            _paint_object(frame, cx, cy, SIZE, i % 2)
            boxes.append([cx - SIZE / 2, cy - SIZE / 2, SIZE, SIZE])
        u8 = (frame.numpy() * 255).round().astype(np.uint8)
        writer.write(cv2.cvtColor(u8, cv2.COLOR_GRAY2BGR))
        cv2.imwrite(str(frames_dir / f"{i:04d}.png"), u8)
    writer.release()
    labels = root / "labels"
    labels.mkdir()
    label = {"video": video.name, "class": "toy", "box_format": "xywh_pixels", "boxes": boxes + [None]}  # one label too many
    (labels / "V_TOY_001.json").write_text(json.dumps(label))
    (labels / "V_OTHER_002.json").write_text(json.dumps({**label, "video": "V_OTHER_002.mp4"}))
    return {"root": root, "ckpt": ckpt, "video": video, "frames": frames_dir, "labels": labels}


def test_detect_video_then_evaluate(workspace: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    out = workspace["root"] / "dets.json"
    rc = cli_main(["detect", "--checkpoint", str(workspace["ckpt"]), "--video", str(workspace["video"]), "--out", str(out), "--scales", "1.0", "--quiet"])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["n_frames"] == N_FRAMES and summary["processed_frames"] == N_FRAMES
    payload = json.loads(out.read_text())
    assert payload["format"] == "synthaug.detections" and payload["detector"] == "hog"
    assert payload["video"] == "V_TOY_001.mp4" and len(payload["detections"]) == N_FRAMES
    for i, frame_dets in enumerate(payload["detections"]):
        assert 1 <= len(frame_dets) <= 10
        assert all(len(d) == 5 for d in frame_dets)
        scores = [d[4] for d in frame_dets]
        assert scores == sorted(scores, reverse=True)
        if i != 3:  # the best box of each frame hits the object
            x, y, w, h, _ = frame_dets[0]
            cx, cy = _centre(i)
            assert abs(x + w / 2 - cx) < 8 and abs(y + h / 2 - cy) < 8

    eval_dir = workspace["root"] / "eval"
    rc = cli_main(["evaluate", "--detections", str(out), "--labels", str(workspace["labels"]), "--out", str(eval_dir)])
    assert rc == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics == json.loads((eval_dir / "metrics.json").read_text())
    assert metrics["n_frames"] == N_FRAMES and metrics["n_ground_truth"] == N_FRAMES - 1
    assert metrics["n_true_positives"] == N_FRAMES - 1
    assert metrics["ap"] > 0.9
    assert list(metrics["per_video"]) == ["V_TOY_001"]
    assert (eval_dir / "pr.png").read_bytes()[:4] == b"\x89PNG"
    assert metrics["unlabelled_frames"] == "score"
    # --unlabelled-frames skip (protocol v2): frame 3, whose label is null, is not scored; its detections go
    rc = cli_main(["evaluate", "--detections", str(out), "--labels", str(workspace["labels"]), "--out",
                   str(workspace["root"] / "eval_skip"), "--unlabelled-frames", "skip"])
    assert rc == 0
    skipped = json.loads(capsys.readouterr().out)
    assert skipped["unlabelled_frames"] == "skip" and skipped["n_frames"] == N_FRAMES - 1
    assert skipped["n_ground_truth"] == metrics["n_ground_truth"]
    assert skipped["n_true_positives"] == metrics["n_true_positives"]
    assert skipped["n_detections"] == metrics["n_detections"] - len(payload["detections"][3])
    assert skipped["ap"] >= metrics["ap"]


def test_frame_stride_gives_nulls_and_evaluate_skips_them(workspace: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    out = workspace["root"] / "dets_stride.json"
    rc = cli_main(
        ["detect", "--checkpoint", str(workspace["ckpt"]), "--images", str(workspace["frames"]), "--out", str(out), "--stride", "2", "--scales", "1.0", "--max-detections", "1", "--quiet"]
    )
    assert rc == 0
    dets = json.loads(out.read_text())["detections"]
    assert len(dets) == N_FRAMES
    assert [d is None for d in dets] == [i % 2 == 1 for i in range(N_FRAMES)]
    assert all(len(d) == 1 for d in dets if d is not None)
    capsys.readouterr()
    label_file = workspace["labels"] / "V_TOY_001.json"
    rc = cli_main(["evaluate", "--detections", str(out), "--labels", str(label_file), "--out", str(workspace["root"] / "eval2")])
    assert rc == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["n_frames"] == 3 and metrics["n_ground_truth"] == 3  # frames 0, 2, 4


def test_detect_errors_are_clear(workspace: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    bad = workspace["root"] / "bad.pt"
    bad.write_bytes(b"\x00garbage")
    rc = cli_main(["detect", "--checkpoint", str(bad), "--video", str(workspace["video"]), "--out", str(workspace["root"] / "x.json")])
    assert rc == 2
    assert "bad.pt" in capsys.readouterr().err
    rc = cli_main(["detect", "--checkpoint", str(workspace["ckpt"]), "--video", str(workspace["root"] / "none.mp4"), "--out", str(workspace["root"] / "x.json")])
    assert rc == 2 and "none.mp4" in capsys.readouterr().err
    rc = cli_main(["detect", "--checkpoint", str(workspace["ckpt"]), "--video", str(workspace["video"]), "--out", str(workspace["root"] / "x.json"), "--frame-stride", "0"])
    assert rc == 2 and "--frame-stride" in capsys.readouterr().err


def test_evaluate_pairing_errors(workspace: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    dets = workspace["root"] / "orphan.json"
    dets.write_text(json.dumps({"video": "V_MISSING_009.mp4", "detections": [[]]}))
    rc = cli_main(["evaluate", "--detections", str(dets), "--labels", str(workspace["labels"]), "--out", str(workspace["root"] / "e")])
    assert rc == 2 and "V_MISSING_009" in capsys.readouterr().err
    broken = workspace["root"] / "broken.json"
    broken.write_text(json.dumps({"video": "V_TOY_001.mp4", "detections": [[[1, 2, 3]]]}))
    rc = cli_main(["evaluate", "--detections", str(broken), "--labels", str(workspace["labels"]), "--out", str(workspace["root"] / "e")])
    assert rc == 2 and "broken.json" in capsys.readouterr().err


@pytest.mark.real_data
def test_detect_and_evaluate_on_a_real_video(shared_data: Path, workspace: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Smoke run on a real halmstad video: format, frame count and pairing with the shared labels."""
    video = shared_data / "halmstad" / "videos" / "V_DRONE_001.mp4"
    out = tmp_path / "real.json"
    rc = cli_main(["detect", "--checkpoint", str(workspace["ckpt"]), "--video", str(video), "--out", str(out), "--stride", "50", "--max-frames", "120", "--quiet"])
    assert rc == 0
    dets = json.loads(out.read_text())["detections"]
    assert len(dets) == 120 and [i for i, d in enumerate(dets) if d is not None] == [0, 50, 100]
    capsys.readouterr()
    rc = cli_main(["evaluate", "--detections", str(out), "--labels", str(shared_data / "halmstad" / "labels"), "--out", str(tmp_path / "eval")])
    assert rc == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["n_frames"] == 3 and metrics["per_video"].keys() == {"V_DRONE_001"}
