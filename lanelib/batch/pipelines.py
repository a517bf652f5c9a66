"""The two pipelines' runs over a folder of images or a video, each a thin ``process`` callable on
the shared machinery (``run_images``, ``run_video``, ``run_video_segments``):

- the advanced pipeline (``LanePipeline``, ``LaneTracker`` through a video): ``process_images``,
  ``process_video``;
- the basic Hough pipeline (``hough.HoughLaneFinder``, ``hough.HoughTracker`` through a video):
  ``hough_images``, ``hough_video``.

On Dask the ``process`` callables are built on the workers by picklable factories
(``lane_image_process``, ``lane_video_process``, ``hough_image_process``, ``hough_video_process``).
With the geometry watch (``autogeometry.GeometryWatch``) in a video's state, the evidence it keeps
for later is carried through a segment's record of its checks (``carry_lane_state``), and the
segments that started from the wrong geometry, as the records of the checks show, run again at
once from the one process's (``plan_lane_restarts``).
"""
from __future__ import annotations

import functools
import os
import pickle
from dataclasses import replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .. import cluster, hough, io
from ..autogeometry import GeometryOptions, GeometryWatch, RoadGeometry, geometry_calibration
from ..camera import Calibration
from ..config import PipelineConfig
from ..errors import ConfigError, InputError
from ..pipeline import LanePipeline
from ..result import FrameResult
from ..tracking import LaneTracker
from .geometry import estimate_road_geometry, with_geometry
from .images import ImageFn, run_images
from .segments import FrameState, run_video_segments
from .video import FrameFn, VideoRun, run_video


def lane_image_process(config: PipelineConfig, calibration: Calibration | None, debug: bool) -> ImageFn:
    """Return ``process_images``'s ``process``: one image -> (annotated image or debug composite,
    ``FrameResult.summary``), with one pipeline per frame size, built on first use."""
    cache: dict[tuple[int, int], LanePipeline] = {}

    def process(rgb: np.ndarray) -> tuple[np.ndarray, dict]:
        size = (rgb.shape[1], rgb.shape[0])
        if size not in cache:
            try:
                cache[size] = LanePipeline(config, calibration, size=size)
            except ConfigError:
                LanePipeline(config)  # a bad config raises here again: it fails every image alike
                w, h = config.perspective.size_px
                raise InputError(f"the image is {size[0]}x{size[1]} px, too small for the bird's-eye "
                                 "view (the perspective points collapse when scaled to it); pass "
                                 f"larger images (the config's points are for {w}x{h})") from None
        pipe = cache[size]
        result = pipe.process(rgb, keep_images=debug)
        image = pipe.debug_composite(result) if debug else result.images["result"]
        return image, result.summary()

    return process


def process_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike,
                   config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                   debug: bool = False, workers: int = 1, scheduler: str | None = None,
                   progress: bool = True) -> list[dict]:
    """Return the rows of ``results.json`` after finding the lane in each image and writing it annotated.

    Each row is the image's ``FrameResult.summary``. Frames of several sizes are allowed: one
    pipeline is built per size (the calibration is rescaled or refused per
    ``Calibration.for_size``). A file that cannot be read, an image too small for the bird's-eye
    view, or one whose size the calibration does not fit gets a row with an ``error``
    (``run_images``), and the run goes on. ``debug`` writes the 2x2 debug composite
    (``LanePipeline.debug_composite``) instead of the annotated frame. ``workers``,
    ``scheduler``: the images go in chunks to Dask workers (``cluster.dask_client``,
    ``run_images``; a progress bar unless ``progress`` is false), with the rows of one process.

    Examples
    --------
    >>> import os, tempfile
    >>> from lanelib import data
    >>> with tempfile.TemporaryDirectory() as out:
    ...     rows = process_images([data.bundled("test_images") / "straight_1.jpg"], out, progress=False)
    ...     written = sorted(os.listdir(out))
    >>> rows[0]["file"], rows[0]["found"], written
    ('straight_1.jpg', True, ['results.json', 'straight_1.jpg'])
    """
    make = functools.partial(lane_image_process, config, calibration, debug)
    with cluster.dask_client(workers, scheduler) as client:
        return run_images([Path(f) for f in files], out_dir, None, make=make, client=client,
                          progress=progress)


VIDEO_LOG_COLUMNS = ("frame", "time_s", "found", "method", "left_conf", "right_conf", "radius_m", "offset_m",
                     "lane_width_m", "left_a", "left_b", "left_c", "right_a", "right_b", "right_c",
                     "left_source", "right_source")


def video_log_row(frame: int, time_s: float, result: FrameResult) -> dict:
    """Return one row of the per-frame video log (``VIDEO_LOG_COLUMNS``; NaN where not found).

    The fit coefficients are the tracked bird's-eye pixel fits x = a*y**2 + b*y + c. ``method``
    is how the lane was found: ``windows`` or ``prior`` (seen in this frame), ``hold`` (held
    from earlier frames, not seen in this one), or the search tried when none was found.
    ``left_source``/``right_source`` say where each line comes from (``FrameResult.sources``:
    seen, edge, shoulder, inferred, held, or empty without a line).
    """
    nan = float("nan")
    row = {"frame": frame, "time_s": round(time_s, 4), "found": int(result.found),
           "method": result.method,
           "left_conf": result.left_conf, "right_conf": result.right_conf,
           "radius_m": result.radius_m, "offset_m": result.offset_m,
           "lane_width_m": result.lane_width_m}
    for side, fit in (("left", result.left), ("right", result.right)):
        coeffs = fit.coeffs_px if fit.found else (nan, nan, nan)
        row.update({f"{side}_{k}": v for k, v in zip("abc", coeffs)})
    row["left_source"], row["right_source"] = result.sources
    return row


def process_video(in_path: str | os.PathLike, out_path: str | os.PathLike,
                  config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                  debug: bool = False, log_path: str | os.PathLike | None = None,
                  progress: bool = True, threads: int | None = None, start_s: float | None = None,
                  end_s: float | None = None, auto_geometry: GeometryOptions | None = None,
                  on_geometry: Callable[[RoadGeometry], None] | None = None, workers: int = 1,
                  scheduler: str | None = None) -> VideoRun:
    """Return what the run did after tracking the lane through a video and writing it annotated.

    The lane is drawn on the RAW frames, mapped through the lens model (``config.draw.
    video_undistorted`` draws on undistorted frames instead, at one more remap per frame).

    Parameters
    ----------
    in_path, out_path : input video and output mp4 (H.264, the input's size and frame rate).
    config, calibration : as for ``LanePipeline``; the pipeline is made for the video's frame size.
    debug : write the 2x2 debug composite (undistorted, binary, search, result) instead.
    log_path : per-frame CSV with ``VIDEO_LOG_COLUMNS`` (optional).
    progress : show a tqdm bar with fps and ETA.
    threads : encoder threads (None: ffmpeg's choice).
    start_s, end_s : run on part of the clip (seconds; None: from its start, to its end): the
        frames from the first at or after ``start_s`` to the last before ``end_s``
        (``clip_frames``). The tracker starts fresh on the first of them; the log's ``frame``
        and ``time_s`` are the source clip's (``run_video``).
    auto_geometry : estimate the bird's-eye points and scale from the clip's first
        ``seconds`` (from ``start_s``) instead of ``config.perspective`` (``estimate_road_geometry``:
        a ``GeometryError`` before anything is written when that fails or is not confident), then
        keep checking them (``GeometryWatch``): the vanishing point is refined along the horizon
        as straight road accumulates, and the geometry estimated again when the horizon moves; a
        refined or new geometry restarts the tracker. The run's ``notes`` say when and why.
    on_geometry : called with the first estimate, before the run starts (the CLI prints it).
    workers, scheduler : run the clip in segments on Dask workers (``cluster.dask_client``,
        ``run_video_segments``: each segment starts ``cluster.WARMUP_FRAMES`` early to warm the
        tracker up, and runs again from the previous segment's tracker where that was not
        enough, so the frames and the log are those of one process). With ``auto_geometry`` the
        geometry is estimated once here; the geometry watch is part of the state checked at the
        joints (a drift found in one segment carries over into the next by a re-run); the
        straight checks a refinement rests on are carried through the next segment's record of
        its checks (``carry_lane_state``), which is run again only where they would have
        refined the geometry in it. The checks' points do not depend on the geometry in use, so
        the segments' records tell where one process changes the geometry: the segments that
        started from another geometry than its (every one after a refinement) run again at once
        from its watch (``plan_lane_restarts``; one round, ``VideoRun.joints.rounds``).

    Every output is written atomically by ``run_video``: an error or Ctrl-C leaves nothing under
    ``out_path`` or ``log_path``, except a video that stops decoding half-way: its outputs keep
    the frames before the break, and ``PartialOutputError`` says so.
    """
    geo = None
    if auto_geometry is not None:
        # before the cluster: a failed estimate stops the run before any worker starts
        geo = estimate_road_geometry(in_path, calibration, auto_geometry, start_s)
        calibration = geometry_calibration(calibration, geo)
        if on_geometry is not None:
            on_geometry(geo)
    fps = io.video_info(in_path).fps if geo is not None else None
    make = functools.partial(lane_video_process, config, calibration, debug, geo, auto_geometry, fps)
    with cluster.dask_client(workers, scheduler) as client:
        if client is not None:
            return run_video_segments(in_path, out_path, make, client, log_path=log_path,
                                      progress=progress, desc=Path(in_path).name, threads=threads,
                                      start_s=start_s, end_s=end_s,
                                      carry=carry_lane_state if geo is not None else None,
                                      plan=plan_lane_restarts if geo is not None else None)
    process, notes, _ = make()
    run = run_video(in_path, out_path, process, log_path=log_path, progress=progress,
                    desc=Path(in_path).name, threads=threads, start_s=start_s, end_s=end_s)
    return replace(run, notes=tuple(notes))


def pipeline_for(image: np.ndarray, config: PipelineConfig = PipelineConfig(),
                 calibration: Calibration | None = None) -> LanePipeline:
    """Return a LanePipeline for frames of ``image``'s size."""
    return LanePipeline(config, calibration, size=(image.shape[1], image.shape[0]))


def lane_video_process(config: PipelineConfig, calibration: Calibration | None, debug: bool,
                       geo: RoadGeometry | None = None, auto_geometry: GeometryOptions | None = None,
                       fps: float | None = None) -> tuple[FrameFn, list[str], FrameState]:
    """Return ``process_video``'s ``process`` (a fresh ``LaneTracker`` on the first frame), the
    list its notes go to and its state (the tracker; with ``geo`` also the geometry watch); with
    ``geo``, the road geometry in use, checked (``GeometryWatch`` at ``fps``), refined and
    estimated again when it drifts; a refined or new geometry restarts the tracker."""
    trackers: list[LaneTracker] = []  # made on the first frame, for the video's frame size
    watch: list[GeometryWatch] = []
    if geo is not None:
        config = with_geometry(config, geo)
        watch.append(GeometryWatch(geo, calibration, auto_geometry, fps))

    current = [config]  # the config of the geometry in use

    def process(frame: np.ndarray, index: int, time_s: float) -> tuple[np.ndarray, dict, bool]:
        new = watch[0].check(frame, index, time_s) if watch else None
        if new is not None:
            current[0] = with_geometry(config, new)
        if not trackers or new is not None:
            trackers[:] = [LaneTracker(pipeline_for(frame, current[0], calibration))]
        tracker = trackers[0]
        pipe = tracker.pipeline
        result = tracker.update(frame, keep_images=debug, index=index)
        if debug:
            image = pipe.debug_composite(result, raw=frame)
        elif config.draw.video_undistorted:
            image = pipe.annotate(pipe.undistort(frame), result)
        else:
            image = pipe.annotate(frame, result, raw=True)
        return image, video_log_row(index, time_s, result), result.found

    def key() -> bytes | None:
        return _lane_state_key(trackers[0] if trackers else None, watch[0] if watch else None)

    def core() -> bytes | None:
        if not trackers or not watch:
            return None
        return trackers[0].state_key() + watch[0].core_key()

    def get() -> object:
        return trackers[0] if trackers else None, current[0], watch[0] if watch else None

    def put(state: object) -> None:
        tracker, current[0], new = state
        trackers[:] = [tracker] if tracker is not None else []
        if new is not None:  # its notes were the other process's: this one's go to the list returned
            new.notes = watch[0].notes
            watch[0] = new

    return process, (watch[0].notes if watch else []), FrameState(key, get, put, core)


def _lane_state_key(tracker: LaneTracker | None, watch: GeometryWatch | None) -> bytes | None:
    """Return the fingerprint of ``lane_video_process``'s state: its tracker's and watch's."""
    if tracker is None:
        return None
    return tracker.state_key() + (watch.state_key() if watch is not None else b"")


def carry_lane_state(before: object, state: object, start: int) -> tuple[object, bytes] | None:
    """Return ``lane_video_process``'s state ``state`` (a segment's end, from a fresh start)
    with the geometry watch of ``before`` (the previous segment's end) carried through the
    segment's straight checks from frame ``start`` (``GeometryWatch.carried_through``), and its
    key; None when that would have changed the geometry (the segment must run again)."""
    tracker, config, watch = state
    watch = before[2].carried_through(watch, start) if watch is not None and before[2] is not None else None
    if watch is None:
        return None
    return (tracker, config, watch), _lane_state_key(tracker, watch)


def plan_lane_restarts(fresh: object, ends: Sequence[object], spans: Sequence[tuple[int, int, int, bool]]
                       ) -> dict[int, object]:
    """Return, for each Dask segment that started from the wrong geometry, the state of
    ``lane_video_process`` to run it again from, from its first (warm-up) frame: a fresh tracker
    and the geometry watch of one process at that frame (``cluster.settle_joints``' plan).

    ``fresh``: the state every segment started from (the first estimate, a fresh watch);
    ``ends``: the segments' end states after that start, in order; ``spans``: their
    ``(first, start, stop, to_end)``. The watch's checks measure the same points whatever the
    geometry in use (``GeometryWatch.replayed``), so a fresh watch carried through the segments'
    records frame by frame is the one process's watch: where its geometry at a segment's first
    frame, or its changes in the segment, differ from the fresh start's (a refinement in an
    earlier segment, or in this one on evidence from before it), the segment is planned to run
    again with it. The tracker is restarted by the geometry's change in one process, and warms
    up with the right geometry here; the joints' keys check the rest (a restarted segment that
    still did not settle runs again from the state before it). The plan ends (the later
    segments are left to the joints' checks) where the records cannot tell: a new estimate due
    (it takes the frames), checks off the horizon pending at a segment's first frame, a record
    that lost checks, a segment without a watch.
    """
    _, config, watch = fresh
    plan: dict[int, object] = {}
    if watch is None:
        return plan
    first_geometry = watch.geometry
    for k, end in enumerate(ends):
        own = end[2]
        first, _, stop, _ = spans[k]
        if own is None or own.recorded > len(own.record) or watch.off:
            break
        checks = list(own.record)  # the segment's checks from its first frame on
        if k > 0:
            got = watch.replayed([c for c in checks if c[0] < stop])
            if got is None:
                break
            if watch.geometry != first_geometry or got[1] or own.changed_at >= 0:
                start_watch = pickle.loads(pickle.dumps(watch))
                start_watch.notes = []
                plan[k] = (None, with_geometry(config, watch.geometry), start_watch)
        if k + 1 < len(ends):
            got = watch.replayed([c for c in checks if c[0] < spans[k + 1][0]])
            if got is None:
                break
            watch = got[0]
    return plan


def hough_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike,
                 config: hough.HoughConfig = hough.HoughConfig(), workers: int = 1,
                 scheduler: str | None = None, progress: bool = True) -> list[dict]:
    """Return the rows of ``results.json`` after finding the lines in each image and writing it annotated.

    Each row holds ``file``, ``left_found``, ``right_found``, each line's x (px) at the bottom
    row and at the top of the region (None when not found), and ``reason``
    (``HoughResult.row``); a file that cannot be read holds ``file`` and ``error`` instead, and
    the run goes on (``run_images``). ``workers``, ``scheduler``: on Dask, as ``process_images``.
    """
    make = functools.partial(hough_image_process, config)
    with cluster.dask_client(workers, scheduler) as client:
        return run_images(files, out_dir, None, make=make, client=client, progress=progress)


def hough_image_process(config: hough.HoughConfig) -> ImageFn:
    """Return ``hough_images``'s ``process``: one image -> (annotated, ``HoughResult.row``)."""
    finder = hough.HoughLaneFinder(config)

    def process(rgb: np.ndarray) -> tuple[np.ndarray, dict]:
        result = finder.process(rgb)
        return hough.annotate(rgb, result), result.row()

    return process


def hough_log_row(frame: int, time_s: float, result: hough.HoughResult) -> dict:
    """Return one row of the per-frame Hough video log: ``frame``, ``time_s`` and ``HoughResult.row``."""
    return {"frame": frame, "time_s": time_s, **result.row()}


def hough_video(in_path: str | os.PathLike, out_path: str | os.PathLike,
                config: hough.HoughConfig = hough.HoughConfig(),
                log_path: str | os.PathLike | None = None, progress: bool = True,
                threads: int | None = None, start_s: float | None = None,
                end_s: float | None = None, workers: int = 1, scheduler: str | None = None) -> VideoRun:
    """Return what the run did after tracking both lines through a video and writing it annotated.

    ``out_path`` is an H.264 video with the input's size and frame rate; the optional per-frame
    CSV at ``log_path`` holds ``hough_log_row``. ``found_frames`` counts frames with both lines
    (measured or held). ``start_s``, ``end_s`` run on part of the clip, as for
    ``process_video``. Outputs are written atomically by ``run_video``: an error or Ctrl-C
    leaves nothing behind, except a video that stops decoding half-way: its outputs keep the
    frames before the break, and ``PartialOutputError`` says so. ``workers``, ``scheduler``: in
    segments on Dask, as ``process_video``.
    """
    if Path(out_path).suffix.lower() not in io.VIDEO_SUFFIXES:
        raise InputError(f"{out_path}: the output video needs a video suffix "
                         f"({', '.join(io.VIDEO_SUFFIXES)}); e.g. out.mp4")
    make = functools.partial(hough_video_process, config)
    with cluster.dask_client(workers, scheduler) as client:
        if client is not None:
            # a warm-up its smoothing forgets a start in, to the last bit (most joints settle)
            return run_video_segments(in_path, out_path, make, client, log_path=log_path,
                                      progress=progress, desc=Path(in_path).name, threads=threads,
                                      start_s=start_s, end_s=end_s, warmup=hough.settle_frames(config))
    return run_video(in_path, out_path, make()[0], log_path=log_path, progress=progress,
                     desc=Path(in_path).name, threads=threads, start_s=start_s, end_s=end_s)


def hough_video_process(config: hough.HoughConfig) -> tuple[FrameFn, list[str], FrameState]:
    """Return ``hough_video``'s ``process`` (a fresh ``HoughTracker``), its (empty) notes and its
    state (the tracker)."""
    tracker = [hough.HoughTracker(config)]

    def process(frame: np.ndarray, index: int, time_s: float) -> tuple[np.ndarray, dict, bool]:
        result = tracker[0].process(frame)
        return (hough.annotate(frame, result), hough_log_row(index, time_s, result),
                result.left_found and result.right_found)

    def put(state: object) -> None:
        tracker[0] = state

    return process, [], FrameState(lambda: tracker[0].state_key(), lambda: tracker[0], put)
