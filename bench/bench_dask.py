"""Frames per second of ``predict tusimple``, ``video`` and ``evaluate video`` in one process and on
1 and 2 Dask workers, and the peak memory of each worker (``--what``; default: predict).

predict: on a synthetic TuSimple set.

The set (``--frames``, default 2,000 as in issue 17) is rendered first by ``python -m lanelib synth
dataset tusimple`` in a child process (its time is printed; about 0.1 s a frame, so ~4 min for
2,000), or taken from ``--root``. Each run predicts every frame into a fresh folder with
``--auto-geometry`` (the geometry is estimated once per sequence in the client, as the CLI does).
The Dask runs use a ``LocalCluster`` of N one-thread processes started before the clock (its
start-up time is printed apart, its workers with glibc's default malloc trimming as
``--workers`` starts them: ``cluster.WORKER_CONFIG``) and passed as ``scheduler``, as
``--scheduler`` would; a worker's
peak memory is its process's peak resident set (``VmHWM``) at the end. The one-process figure
is this process's peak, which holds lanelib and the run only (the rendering is another process).

video, evaluate: ``process_video`` (annotated video and per-frame log) and ``evaluate_video``
(tracker) on ``--video`` (default videos/project.mp4, with its truth), the clip split into
segments that start ``cluster.WARMUP_FRAMES`` early (their frames are counted once: the
figure is the clip's frames over the wall time, start-up of the cluster apart). The one-process
peak of these runs is not printed (this process also held the earlier runs).

    .venv/bin/python bench/bench_dask.py [--what predict video evaluate] [--frames 2000] [--root DIR]
        [--video FILE] [--workers 1 2]
"""
from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import dask
import distributed

from lanelib import autogeometry, batch, cluster, evaluate
from lanelib.config import PipelineConfig
from lanelib.pipeline import LanePipeline

REPO = Path(__file__).resolve().parents[1]


def peak_rss_mb() -> float:
    """Return this process's peak resident set in MB (Linux's VmHWM; ru_maxrss would carry the
    parent's peak over into a spawned worker)."""
    status = Path("/proc/self/status")
    if status.is_file():
        for line in status.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def predict(root: Path, out: Path, **kwargs) -> batch.PredictRun:
    run = batch.predict_benchmark("tusimple", root, out, config=PipelineConfig(), progress=False,
                                  auto_geometry=autogeometry.GeometryOptions(accept_low_confidence=True), **kwargs)
    assert not run.failed, run.failed[:3]
    return run


def local_clusters(counts):
    """Yield (workers, scheduler address, client, start-up seconds) of a LocalCluster per count,
    started as ``--workers`` starts one (one-thread processes, glibc's malloc trimming)."""
    for n in counts:
        t0 = time.perf_counter()
        with dask.config.set(cluster.WORKER_CONFIG), \
                distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                         dashboard_address=None) as local, \
                distributed.Client(local) as client:
            yield n, local.scheduler_address, client, time.perf_counter() - t0


def bench_clip(what: str, video: Path, tmp: Path, counts) -> None:
    """Print the frames/s of ``video`` or ``evaluate video`` on ``video`` in one process and on Dask."""
    def run(scheduler=None, tag="one"):
        t0 = time.perf_counter()
        if what == "video":
            r = batch.process_video(video, tmp / f"{tag}.mp4", log_path=tmp / f"{tag}.csv", progress=False,
                                    scheduler=scheduler)
            frames = r.frames
        else:
            pipe = LanePipeline(calibration=evaluate.calibration_from_truth(video))
            frames = evaluate.evaluate_video(video, pipe, scheduler=scheduler, progress=False).frames
        return frames, time.perf_counter() - t0

    n, sec = run()
    print(f"{what:8s} one process (no Dask)  {n:5d} frames in {sec:6.1f} s  {n / sec:5.1f} frames/s")
    for k, address, client, start in local_clusters(counts):
        n, sec = run(address, f"dask{k}")
        peaks = client.run(peak_rss_mb)
        same = ""
        if what == "video":
            same = ("; log = one process's" if (tmp / f"dask{k}.csv").read_text() == (tmp / "one.csv").read_text()
                    else "; LOG DIFFERS from one process's")
        print(f"{what:8s} Dask, {k} worker{'s' if k > 1 else ' '}      {n:5d} frames in {sec:6.1f} s  "
              f"{n / sec:5.1f} frames/s  peak per worker " + ", ".join(f"{p:.0f}" for p in peaks.values())
              + f" MB  (cluster start-up {start:.1f} s){same}")


def main() -> None:
    """Print frames/s and peak memory per worker for each run."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--what", nargs="+", choices=("predict", "video", "evaluate"), default=["predict"],
                    help="what to time (default: predict)")
    ap.add_argument("--frames", type=int, default=2000, help="predict: frames to render (default: 2000)")
    ap.add_argument("--root", type=Path, help="predict: an existing synthetic TuSimple set (no rendering)")
    ap.add_argument("--video", type=Path, default=REPO / "videos/project.mp4",
                    help="video, evaluate: the clip (default: videos/project.mp4; evaluate needs its truth)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="Dask worker counts (default: 1 2)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_dask_") as tmp:
        if "predict" in args.what:  # first: its one-process peak is this process's
            bench_predict(args, Path(tmp))
        for what in args.what:
            if what != "predict":
                bench_clip(what, args.video, Path(tmp), args.workers)


def bench_predict(args, tmp: Path) -> None:
    """Print the frames/s and peak memory of ``predict tusimple`` in one process and on Dask."""
    root = args.root
    if root is None:
        root = tmp / "tusimple"
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "lanelib", "synth", "dataset", "tusimple", "-o", str(root),
                        "--frames", str(args.frames)], check=True, stdout=subprocess.DEVNULL)
        print(f"rendered {args.frames} frames in {time.perf_counter() - t0:.0f} s")
    run = predict(root, tmp / "one")
    print(f"predict  one process (no Dask)  {run.frames:5d} frames in {run.seconds:6.1f} s  "
          f"{run.frames / run.seconds:5.1f} frames/s  peak {peak_rss_mb():4.0f} MB")
    for n, address, client, start in local_clusters(args.workers):
        run = predict(root, tmp / f"dask{n}", scheduler=address)
        peaks = client.run(peak_rss_mb)
        print(f"predict  Dask, {n} worker{'s' if n > 1 else ' '}      {run.frames:5d} frames in {run.seconds:6.1f} s  "
              f"{run.frames / run.seconds:5.1f} frames/s  peak per worker "
              + ", ".join(f"{p:.0f}" for p in peaks.values()) + f" MB  (cluster start-up {start:.1f} s)")


if __name__ == "__main__":
    main()
