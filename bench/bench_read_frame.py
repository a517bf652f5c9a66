"""Milliseconds to get one frame of a video: ``io.read_frame`` (seek) against sequential decoding.

``io.read_frame`` seeks with ffmpeg's ``-ss`` before ``-i``: it decodes from the key frame before
the wanted frame, not from the start. Sequential decoding (``io.VideoReader``) reads every frame up
to the one wanted. For each index the seek is repeated ``--repeat`` times (the median is printed,
with and without reading the video's info first) and the sequential read once.

    .venv/bin/python bench/bench_read_frame.py [--video videos/project.mp4] [--index 0 120 240]
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from lanelib import io

REPO = Path(__file__).resolve().parents[1]


def _ms(fn) -> tuple[float, object]:
    t0 = time.perf_counter()
    out = fn()
    return (time.perf_counter() - t0) * 1000, out


def _sequential(path: Path, index: int) -> np.ndarray:
    with io.VideoReader(path) as reader:
        for i, frame in enumerate(reader):
            if i == index:
                return frame.copy()
    raise IndexError(index)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--video", default=str(REPO / "videos" / "project.mp4"))
    ap.add_argument("--index", type=int, nargs="+", default=[0, 120, 240])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    path = Path(args.video)
    info_ms, info = _ms(lambda: io.video_info(path))
    print(f"{path.name}: {info.width}x{info.height}, {info.n_frames} frames at {info.fps:g} fps; "
          f"video_info {info_ms:.0f} ms")
    print(f"{'frame':>6} {'seek ms':>8} {'seek+info ms':>13} {'sequential ms':>14} {'ratio':>6} same")
    for index in args.index:
        seek = [_ms(lambda: io.read_frame(path, index, info=info)) for _ in range(args.repeat)]
        with_info = statistics.median(_ms(lambda: io.read_frame(path, index))[0]
                                      for _ in range(max(1, args.repeat // 2)))
        seq_ms, frame = _ms(lambda: _sequential(path, index))
        seek_ms = statistics.median(ms for ms, _ in seek)
        same = all(np.array_equal(f, frame) for _, f in seek)
        print(f"{index:>6} {seek_ms:>8.0f} {with_info:>13.0f} {seq_ms:>14.0f} "
              f"{seq_ms / seek_ms:>5.1f}x {'yes' if same else 'NO'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
