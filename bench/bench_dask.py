"""Frames per second of ``predict tusimple`` in one process and on 1 and 2 Dask workers, and the
peak memory of each worker, on a synthetic TuSimple set.

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

    .venv/bin/python bench/bench_dask.py [--frames 2000] [--root DIR] [--workers 1 2]
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

from lanelib import cluster, runs
from lanelib.config import PipelineConfig


def peak_rss_mb() -> float:
    """Return this process's peak resident set in MB (Linux's VmHWM; ru_maxrss would carry the
    parent's peak over into a spawned worker)."""
    status = Path("/proc/self/status")
    if status.is_file():
        for line in status.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def predict(root: Path, out: Path, **kwargs) -> runs.PredictRun:
    run = runs.predict_benchmark("tusimple", root, out, config=PipelineConfig(), progress=False,
                                 auto_geometry=runs.GeometryOptions(accept_low_confidence=True), **kwargs)
    assert not run.failed, run.failed[:3]
    return run


def main() -> None:
    """Print frames/s and peak memory per worker for each run."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=2000, help="frames to render (default: 2000)")
    ap.add_argument("--root", type=Path, help="an existing synthetic TuSimple set (no rendering)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="Dask worker counts (default: 1 2)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_dask_") as tmp:
        root = args.root
        if root is None:
            root = Path(tmp) / "tusimple"
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "lanelib", "synth", "dataset", "tusimple", "-o", str(root),
                            "--frames", str(args.frames)], check=True, stdout=subprocess.DEVNULL)
            print(f"rendered {args.frames} frames in {time.perf_counter() - t0:.0f} s")
        run = predict(root, Path(tmp) / "one")
        print(f"one process (no Dask)  {run.frames:5d} frames in {run.seconds:6.1f} s  "
              f"{run.frames / run.seconds:5.1f} frames/s  peak {peak_rss_mb():4.0f} MB")
        for n in args.workers:
            t0 = time.perf_counter()
            with dask.config.set(cluster.WORKER_CONFIG), \
                    distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                             dashboard_address=None) as local, \
                    distributed.Client(local) as client:
                start = time.perf_counter() - t0
                run = predict(root, Path(tmp) / f"dask{n}", scheduler=local.scheduler_address)
                peaks = client.run(peak_rss_mb)
            print(f"Dask, {n} worker{'s' if n > 1 else ' '}      {run.frames:5d} frames in {run.seconds:6.1f} s  "
                  f"{run.frames / run.seconds:5.1f} frames/s  peak per worker "
                  + ", ".join(f"{p:.0f}" for p in peaks.values()) + f" MB  (cluster start-up {start:.1f} s)")


if __name__ == "__main__":
    main()
