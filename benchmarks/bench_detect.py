"""Benchmark: multi-scale sliding-window detection speed over one 640x512 frame.

    python benchmarks/bench_detect.py [--repeats 7] [--threads 1] [--scales 1.25 1 0.8 0.64 0.51 0.41]
                                      [--checkpoint runs/hog.pt ...] [--kinds hog adaboost cnn]

For every registered detector kind that can be built here (trained for a few
seconds on generated toy patches: the speed of a linear filter or a stump
cascade barely depends on what it learned), or for every ``--checkpoint``
given, times ``detect_multiscale`` on a real halmstad frame (a generated one
when ../shared/data is absent) at the default pyramid (6 scales, ratio 1.25)
and prints one JSON object with the median frames/s per detector, the
per-stage split (pyramid + score maps vs NMS) and the issue's targets
(HOG >= 10, AdaBoost >= 10, CNN >= 20 frames/s).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path
from typing import Any, Callable

import torch

REPO = Path(__file__).resolve().parents[1]
TARGETS = {"hog": 10.0, "adaboost": 10.0, "cnn": 20.0}


def _frame() -> tuple[torch.Tensor, str]:
    video = REPO.parent / "shared/data/halmstad/videos/V_DRONE_001.mp4"
    if video.is_file():
        import cv2

        cap = cv2.VideoCapture(str(video))
        ok, bgr = cap.read()
        cap.release()
        if ok:
            gray = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
            return torch.from_numpy(gray).float().div(255.0), video.name
    g = torch.Generator().manual_seed(0)
    return (0.5 + 0.1 * torch.rand(512, 640, generator=g)).clamp(0, 1), "generated"


def _toy_data() -> tuple[torch.Tensor, torch.Tensor]:
    try:
        from synthaug.detectors.toy import toy_patches

        return toy_patches(150, 400, seed=0)
    except ImportError:
        g = torch.Generator().manual_seed(0)
        pos = torch.rand(150, 1, 40, 40, generator=g) * 0.3
        pos[:, :, 14:26, 8:32] += 0.6
        return pos, torch.rand(400, 1, 40, 40, generator=g)


def _builders() -> dict[str, Callable[[torch.Tensor, torch.Tensor], Any]]:
    def hog(pos: torch.Tensor, neg: torch.Tensor) -> Any:
        from synthaug.detectors.hog_dpm import HOGDetector

        return HOGDetector.fit(pos, neg, components=3, mining_rounds=1, generator=torch.Generator().manual_seed(0))

    def adaboost(pos: torch.Tensor, neg: torch.Tensor) -> Any:
        from synthaug.detectors.adaboost import train_adaboost

        det = train_adaboost(pos, neg, n_rounds=100, candidates=2000, seed=0)
        if hasattr(det, "calibrate_cascade"):
            det.calibrate_cascade(pos)
        return det

    return {"hog": hog, "adaboost": adaboost}


def _time_detector(det: Any, frame: torch.Tensor, scales: list[float], repeats: int) -> dict[str, Any]:
    from synthaug.detectors.sliding import detect_multiscale, resize_image

    image = frame[None, None]
    detect_multiscale(det, frame, scales=scales)  # warm-up (allocator, lazy imports)
    totals, maps, cpu = [], [], []
    n_out = 0
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        out = detect_multiscale(det, frame, scales=scales, max_detections=10)
        totals.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        n_out = int(out.shape[0])
        t0 = time.perf_counter()
        with torch.no_grad():
            for s in scales:
                det.score_map(resize_image(image, s))
        maps.append(time.perf_counter() - t0)
    median = statistics.median(totals)
    return {
        "frames_per_second": round(1.0 / median, 2),
        "median_ms_per_frame": round(1000 * median, 1),
        "median_ms_pyramid_and_score_maps": round(1000 * statistics.median(maps), 1),
        # CPU seconds of this process: robust to other jobs sharing the machine
        "median_cpu_ms_per_frame": round(1000 * statistics.median(cpu), 1),
        "window": det.window,
        "stride": det.stride,
        "detections_returned": n_out,
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--threads", type=int, default=1, help="torch threads (default 1, as `synthaug detect`)")
    p.add_argument("--scales", type=float, nargs="+", default=None)
    p.add_argument("--kinds", nargs="+", default=None, help="detector kinds to build (default: all registered)")
    p.add_argument("--checkpoint", type=Path, nargs="*", default=[], help="time these checkpoints instead of building toy detectors")
    args = p.parse_args()

    from synthaug.detectors.base import get_detector_class, list_detectors, load_detector
    from synthaug.detectors.sliding import DEFAULT_SCALES

    if args.threads:
        torch.set_num_threads(args.threads)
    scales = list(args.scales or DEFAULT_SCALES)
    frame, source = _frame()
    results: dict[str, Any] = {}
    if args.checkpoint:
        for path in args.checkpoint:
            det = load_detector(path)
            results[f"{det.kind}:{path.name}"] = _time_detector(det, frame, scales, args.repeats)
    else:
        pos, neg = _toy_data()
        builders = _builders()
        for kind in args.kinds or list_detectors():
            cls = get_detector_class(kind)
            build = builders.get(kind) or (lambda pos, neg, cls=cls: cls.example(torch.Generator().manual_seed(0)) if hasattr(cls, "example") else None)
            try:
                t0 = time.perf_counter()
                det = build(pos, neg)
                train_s = time.perf_counter() - t0
            except Exception as e:  # report, do not hide, a kind that cannot be built here
                results[kind] = {"skipped": f"{type(e).__name__}: {e}"}
                continue
            if det is None:
                results[kind] = {"skipped": "no toy builder for this kind (pass --checkpoint)"}
                continue
            results[kind] = {**_time_detector(det, frame, scales, args.repeats), "toy_training_seconds": round(train_s, 1)}
    for name, r in results.items():
        kind = name.split(":")[0]
        if kind in TARGETS and "frames_per_second" in r:
            r["target_frames_per_second"] = TARGETS[kind]
            r["meets_target"] = r["frames_per_second"] >= TARGETS[kind]
    print(
        json.dumps(
            {
                "benchmark": "sliding_window_detection",
                "frame": f"{source} {frame.shape[1]}x{frame.shape[0]}",
                "scales": scales,
                "repeats": args.repeats,
                "torch_threads": torch.get_num_threads(),
                "cpu": platform.processor() or platform.machine(),
                "torch": torch.__version__,
                "detectors": results,
            },
            indent=2,
        )
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
