"""Speed figures: the per-frame detection path against one remap, the video command against the codec.

``python -m lanelib bench [--json]`` prints, from one run:

- ``detect_ms``: the per-frame detection path of a video run, ``LanePipeline.detect`` with the
  previous frame's fits as prior (undistort and warp in one remap, thresholds, search, fits,
  measurements) on consecutive 1280x720 frames, one OpenCV thread; ``remap_ms``: one full-frame
  ``cv2.remap`` of the same colour frames with the pipeline's precomputed bird's-eye maps, one
  thread, interleaved with it; ``detect_to_remap`` = their ratio (goal <= 2.5).
- ``video_fps``: the whole ``video`` command (``batch.process_video``: decode, track, draw,
  encode) on a 1280x720 clip; ``codec_fps``: decode plus encode of the same clip with the same
  encoder settings (``batch.video.H264_PARAMS`` through ``batch.video.VideoWriter``) and nothing else;
  ``video_to_codec`` = their ratio (goal >= 0.7). The two runs alternate and the faster of each
  counts, so a burst of load on the machine does not decide the ratio. Beside them, the CPU
  time per frame of each run (this process and its ffmpeg children): their ratio is what the
  fps ratio tends to when CPU is the limit, and it does not depend on other load.
- ``robust_ms``: ``LanePipeline.detect`` with no prior on the first frames of a hard clip (the
  Udacity challenge video when present, else the bundled ``videos/challenge.mp4``), where the
  whole view's lane fails its checks and, with the ``hard-roads`` preset's parts switched on
  (``ROBUST``), every fallback search runs (``proposers.choose``), one thread, interleaved with
  a remap of the same frames; ``robust_to_remap`` = their ratio (goal <= 3). Beside it,
  ``default_to_remap``: the same frames with the default config, whose opt-in parts are off.
- ``stages_ms``: each stage alone on the same frames (one thread): the remap, the thresholds and
  each mask the rule uses, the searches, the measurements, the tracker's update, the overlay on
  the raw frame (the video path) and the full-frame undistort the images path and --debug add;
  and the road geometry's per-frame vanishing point (``autogeometry.RoadLineFinder``), which
  ``--auto-geometry`` runs twice a second through a video.
- ``fallbacks``: per clip (the benchmarked clip and each bundled synthetic clip), with the
  ``hard-roads`` parts switched on as for ``robust_ms``, the tracker's share of frames that
  needed a fallback search (``LaneTracker.retries``: windows
  from the track, remembered bases, shorter views, other peaks), how often each ran, and the
  median CPU time of ``LaneTracker.update`` (one thread) on the frames that needed none and on
  those that did: how often the robust path runs and what it costs.
- ``geometry_s``: ``--auto-geometry``'s estimate (``autogeometry.estimate_geometry``) from the frames
  it reads (up to 50 of the clip's first 20 s), CPU and wall seconds, without the decoding.

Single-thread timings are CPU time of the timing thread (``time.thread_time``), which a busy
machine does not inflate; the wall-clock medians are printed beside them. The clip is the
Udacity project video when the Udacity data is present (``LANELIB_DATA``, default
``../shared/data``), else the bundled synthetic ``videos/project.mp4``; ``--video`` chooses another.
"""
from __future__ import annotations

import os
import resource
import statistics
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from . import autogeometry, data, io, thresholds
from .camera import Calibration
from .config import PipelineConfig, override, preset_settings
from .errors import InputError, LaneLibError
from .evaluate import calibration_from_truth
from .pipeline import LanePipeline
from .autogeometry import GeometryOptions
from .batch import process_video, sample_frames
from .batch.video import VideoWriter
from .tracking import LaneTracker

GOALS = {"detect_to_remap": ("<=", 2.5), "video_to_codec": (">=", 0.7), "robust_to_remap": ("<=", 3.0)}
ROBUST = preset_settings("hard-roads")  # the parts the robust path's figures switch on
ROBUST_FRAMES = 20  # the hard clip's first frames that robust_ms reads


def default_video() -> tuple[Path, Calibration | None]:
    """Return the clip to benchmark and its calibration (Udacity data first, then the bundled video)."""
    udacity = data.udacity("videos/project_video.mp4")
    if udacity is not None:
        return udacity, data.udacity_calibration()
    synth = data.bundled("videos") / "project.mp4"
    if synth.is_file():
        return synth, calibration_from_truth(synth)
    raise InputError(f"no video to benchmark: neither the Udacity project video "
                     f"({data.missing_reason('videos/project_video.mp4')}) nor {synth}; pass --video, "
                     "or run `python -m lanelib synth --all`")


@contextmanager
def one_thread():
    """Run the block with OpenCV on one thread (restored afterwards)."""
    before = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        yield
    finally:
        cv2.setNumThreads(before)


def _timed(fn: Callable[[], object]) -> tuple[float, float]:
    """Return (thread CPU ms, wall ms) of one call."""
    c0, w0 = time.thread_time(), time.perf_counter()
    fn()
    return (time.thread_time() - c0) * 1e3, (time.perf_counter() - w0) * 1e3


def stage_times(pipe, frames: list[np.ndarray], repeats: int = 3) -> dict[str, dict[str, float]]:
    """Return {stage: {"cpu_ms", "wall_ms"}} medians over ``frames`` x ``repeats``, one thread.

    ``detect`` and ``remap`` are timed in alternation on every frame; the other stages after.
    """
    samples: dict[str, list[tuple[float, float]]] = {}

    def add(name, fn):
        samples.setdefault(name, []).append(_timed(fn))

    with one_thread():
        for _ in range(repeats):
            prior = None
            for raw in frames:
                out = {}
                add("remap", lambda: pipe.birdseye(raw))
                add("detect", lambda: out.setdefault("r", pipe.detect(raw, prior=prior)))
                r = out["r"]
                prior = (r.left, r.right) if r.found else None
        birds = [pipe.birdseye(f) for f in frames]
        masks = [pipe.binary(b) for b in birds]
        first = pipe.search(masks[0])
        prior = (first.left, first.right)
        rule_names = thresholds.rule_masks(pipe.config.thresholds)
        for _ in range(repeats):
            for raw, bird, mask in zip(frames, birds, masks):
                add("detect, no prior (windows)", lambda: pipe.detect(raw))
                add("band_binary (prior bands)", lambda: pipe.band_binary(raw, prior))
                add("thresholds (full view)", lambda: pipe.binary(bird))
                for name in rule_names:
                    spec = getattr(pipe.config.thresholds, name)
                    add(f"  mask {name}", lambda: thresholds.mask(thresholds.Channels(bird), spec))
                add("search, prior", lambda: pipe.search(mask, prior))
                add("search, windows", lambda: pipe.search(mask))
                add("measure", lambda: pipe.measure(prior[0], prior[1]))
                add("undistort (images, --debug)", lambda: pipe.undistort(raw))
        result = pipe.detect(frames[0])
        for _ in range(repeats * len(frames)):
            add("annotate raw (video path)", lambda: pipe.annotate(frames[0], result, raw=True))
        for _ in range(repeats):
            tracker = LaneTracker(pipe)
            for raw in frames:
                add("tracker update", lambda: tracker.update(raw))
        finder = autogeometry.RoadLineFinder(pipe.size, lens=pipe.lens)
        for _ in range(repeats):
            for raw in frames:
                add("vanishing point (geometry)", lambda: finder.vanishing_point(raw))
    return {k: {"cpu_ms": statistics.median(c for c, _ in v), "wall_ms": statistics.median(w for _, w in v)}
            for k, v in samples.items()}


def robust_times(config: PipelineConfig, repeats: int = 3) -> dict[str, float | str]:
    """Return the median CPU ms of ``detect`` without a prior and of a remap on the first
    ``ROBUST_FRAMES`` frames of the hard clip (see the module docstring), one thread."""
    clip, calibration = data.challenge_video(), None
    if clip is not None:
        calibration = data.udacity_calibration()
    else:
        clip = data.bundled("videos") / "challenge.mp4"
        calibration = calibration_from_truth(clip)
    with io.VideoReader(clip, 0, ROBUST_FRAMES) as reader:
        frames = list(reader)
    pipe = LanePipeline(config, calibration, size=(frames[0].shape[1], frames[0].shape[0]))
    detect, remap = [], []
    with one_thread():
        for _ in range(repeats):
            for raw in frames:
                remap.append(_timed(lambda: pipe.birdseye(raw))[0])
                detect.append(_timed(lambda: pipe.detect(raw))[0])
    return {"source": str(clip), "detect_ms": statistics.median(detect), "remap_ms": statistics.median(remap)}


FALLBACK_CLIPS = ("project", "challenge", "harder", "shadows", "seams", "glare", "country")


def fallback_figures(clip: Path, calibration: Calibration | None, config: PipelineConfig,
                     max_frames: int | None = None) -> dict:
    """Return how often the tracker needed a fallback search on ``clip`` and what it cost.

    ``LaneTracker.update`` runs on every frame (up to ``max_frames``) on one thread; each frame
    counts as "fallback" when ``LaneTracker.retries`` is not empty. CPU times are medians
    (``time.thread_time``); a share with no frames gives None.
    """
    cheap, fallback = [], []
    counts: dict[str, int] = {}
    with one_thread(), io.VideoReader(clip) as reader:
        tracker = LaneTracker(LanePipeline(config, calibration, size=reader.info.size))
        for i, raw in enumerate(reader):
            if max_frames is not None and i >= max_frames:
                break
            cpu, _ = _timed(lambda: tracker.update(raw))
            (fallback if tracker.retries else cheap).append(cpu)
            for name in tracker.retries:
                counts[name] = counts.get(name, 0) + 1
    n = len(cheap) + len(fallback)

    def med(v):
        return round(statistics.median(v), 2) if v else None

    return {"frames": n, "fallback_pct": round(100.0 * len(fallback) / max(n, 1), 1),
            "cpu_ms_cheap": med(cheap), "cpu_ms_fallback": med(fallback),
            "cpu_ms_mean": round(statistics.fmean(cheap + fallback), 2) if n else None,
            "runs": counts}


def _clock() -> tuple[float, float]:
    """Return (wall s, CPU s of this process and its finished children, ffmpeg included)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.perf_counter(), me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _rates(start: tuple[float, float], frames: int) -> tuple[float, float]:
    """Return (frames per wall second, CPU ms per frame) since ``start``."""
    wall, cpu = _clock()
    return frames / (wall - start[0]), (cpu - start[1]) * 1e3 / frames


def codec_run(clip: Path, out: Path) -> tuple[float, float]:
    """Return (fps, CPU ms per frame) of decoding ``clip`` and encoding it again, nothing else."""
    start = _clock()
    n = 0
    with io.VideoReader(clip) as reader, VideoWriter(out, reader.info.fps, inputs=[clip]) as writer:
        for frame in reader:
            writer.write(frame)
            n += 1
    return _rates(start, n)


def video_run(clip: Path, out: Path, config: PipelineConfig,
              calibration: Calibration | None) -> tuple[float, float]:
    """Return (fps, CPU ms per frame) of the ``video`` command's work (``process_video``) on ``clip``."""
    start = _clock()
    run = process_video(clip, out, config, calibration, progress=False)
    return _rates(start, run.frames)


def run(video: Path | None = None, calibration: Calibration | None = None,
        config: PipelineConfig = PipelineConfig(), clip_frames: int = 250, stage_frames: int = 60,
        repeats: int = 3, video_rounds: int = 2, fallback_clips: tuple[str, ...] = FALLBACK_CLIPS,
        fallback_frames: int | None = None) -> dict:
    """Return the benchmark figures (see the module docstring) as a JSON-able dict.

    ``fallback_clips`` names the bundled clips (``videos/NAME.mp4``) whose fallback figures are
    measured beside the benchmarked clip's, each on up to ``fallback_frames`` frames (all).
    """
    if video is None:
        video, cal = default_video()
        calibration = calibration or cal
    with tempfile.TemporaryDirectory(prefix="lanelib-bench-") as tmp:
        clip = Path(tmp) / "clip.mp4"
        frames = []
        with io.VideoReader(video) as reader, VideoWriter(clip, reader.info.fps, inputs=[video]) as w:
            size = reader.info.size
            for i, frame in enumerate(reader):
                if i >= clip_frames:
                    break
                w.write(frame)
                if i < stage_frames:
                    frames.append(frame.copy())
        pipe = LanePipeline(config, calibration, size=size)
        stages = stage_times(pipe, frames, repeats)
        hard = override(config, ROBUST)  # the robust path's and the fallbacks' config
        robust = robust_times(hard, repeats)
        plain = robust_times(config, repeats)
        options = GeometryOptions()
        sampled = sample_frames(video, options.seconds, options.max_frames)
        c0, w0 = time.process_time(), time.perf_counter()
        try:
            geo = options.estimate(sampled, calibration)
            geometry_note = f"confidence {geo.confidence:.2f}, {len(geo.frames_used)} frames used"
        except LaneLibError as e:
            geometry_note = f"no estimate: {e}"
        geometry_s = {"cpu_s": round(time.process_time() - c0, 2),
                      "wall_s": round(time.perf_counter() - w0, 2), "frames": len(sampled),
                      "result": geometry_note}
        fallbacks = {video.name: fallback_figures(video, calibration, hard, fallback_frames)}
        for name in fallback_clips:
            synth = data.bundled("videos") / f"{name}.mp4"
            if synth.is_file() and synth.resolve() != Path(video).resolve():
                fallbacks[synth.name] = fallback_figures(synth, calibration_from_truth(synth), hard,
                                                         fallback_frames)
        codec, vid = [], []
        for _ in range(video_rounds):
            codec.append(codec_run(clip, Path(tmp) / "codec.mp4"))
            vid.append(video_run(clip, Path(tmp) / "video.mp4", config, calibration))
    detect, remap = stages["detect"]["cpu_ms"], stages["remap"]["cpu_ms"]
    video_fps, codec_fps = max(v[0] for v in vid), max(c[0] for c in codec)
    video_cpu, codec_cpu = min(v[1] for v in vid), min(c[1] for c in codec)
    figures = {
        "source": str(video), "size": list(size), "calibrated": calibration is not None,
        "detect_ms": round(detect, 2), "remap_ms": round(remap, 2),
        "detect_to_remap": round(detect / remap, 2),
        "robust_ms": round(robust["detect_ms"], 2), "robust_remap_ms": round(robust["remap_ms"], 2),
        "robust_source": robust["source"],
        "robust_to_remap": round(robust["detect_ms"] / robust["remap_ms"], 2),
        "default_ms": round(plain["detect_ms"], 2),
        "default_to_remap": round(plain["detect_ms"] / plain["remap_ms"], 2),
        "video_fps": round(video_fps, 1), "codec_fps": round(codec_fps, 1),
        "video_to_codec": round(video_fps / codec_fps, 2),
        "video_cpu_ms_per_frame": round(video_cpu, 1), "codec_cpu_ms_per_frame": round(codec_cpu, 1),
        "cpu_codec_to_video": round(codec_cpu / video_cpu, 2),
        "stages_ms": {k: {kk: round(vv, 2) for kk, vv in v.items()} for k, v in stages.items()},
        "geometry_s": geometry_s, "fallbacks": fallbacks,
        "video_fps_runs": [round(v[0], 1) for v in vid], "codec_fps_runs": [round(c[0], 1) for c in codec],
        "load_average": [round(v, 2) for v in os.getloadavg()],
        "clip_frames": clip_frames, "stage_frames": len(frames), "cpu_count": os.cpu_count(),
    }
    figures["goals_met"] = {k: _meets(figures[k], *GOALS[k]) for k in GOALS}
    return figures


def _meets(value: float, op: str, goal: float) -> bool:
    return value <= goal if op == "<=" else value >= goal


def format_report(f: dict) -> str:
    """Return the figures as a readable report: headline ratios, then the per-stage table."""
    def goal(key):
        op, g = GOALS[key]
        return f"(goal {op} {g}: {'met' if f['goals_met'][key] else 'MISSED'})"

    lines = [f"source: {f['source']} ({f['size'][0]}x{f['size'][1]}, "
             f"{'calibrated' if f['calibrated'] else 'no calibration'}); {f['cpu_count']} CPUs",
             f"detect_ms       {f['detect_ms']:8.2f}   per frame, prior search, one thread (CPU time)",
             f"remap_ms        {f['remap_ms']:8.2f}   one full-frame colour cv2.remap, same frames",
             f"detect_to_remap {f['detect_to_remap']:8.2f}   {goal('detect_to_remap')}",
             f"robust_ms       {f['robust_ms']:8.2f}   detect, no prior, on the first {ROBUST_FRAMES} frames "
             f"of {Path(f['robust_source']).name} (hard-roads parts: every fallback runs)",
             f"robust_to_remap {f['robust_to_remap']:8.2f}   {goal('robust_to_remap')}",
             f"default_ms      {f['default_ms']:8.2f}   the same frames, default config (opt-in parts off)",
             f"default_to_remap{f['default_to_remap']:8.2f}",
             f"video_fps       {f['video_fps']:8.1f}   `video` on {f['clip_frames']} frames "
             f"(runs: {', '.join(map(str, f['video_fps_runs']))})",
             f"codec_fps       {f['codec_fps']:8.1f}   decode + encode only "
             f"(runs: {', '.join(map(str, f['codec_fps_runs']))})",
             f"video_to_codec  {f['video_to_codec']:8.2f}   {goal('video_to_codec')}",
             f"CPU per frame: video {f['video_cpu_ms_per_frame']:.1f} ms, codec "
             f"{f['codec_cpu_ms_per_frame']:.1f} ms (ffmpeg included), codec/video "
             f"{f['cpu_codec_to_video']:.2f} (the fps ratio when CPU is the limit); "
             f"load average {', '.join(map(str, f['load_average']))}",
             f"geometry_s      {f['geometry_s']['cpu_s']:8.2f}   --auto-geometry's estimate from "
             f"{f['geometry_s']['frames']} frames (CPU s; wall {f['geometry_s']['wall_s']:.2f} s; "
             f"{f['geometry_s']['result']})",
             "",
             f"{'stage (one thread)':28s} {'cpu ms':>8s} {'wall ms':>8s}  x remap"]
    for name, v in f["stages_ms"].items():
        lines.append(f"{name:28s} {v['cpu_ms']:8.2f} {v['wall_ms']:8.2f}  {v['cpu_ms'] / f['remap_ms']:6.2f}")
    lines += ["", "fallback searches of the tracker (LaneTracker.retries), CPU ms per update, one thread",
              f"{'clip':22s} {'frames':>6s} {'fallback %':>10s} {'ms cheap':>9s} {'ms fallback':>11s} "
              f"{'ms mean':>8s}  runs"]

    def ms(v):
        return f"{v:.2f}" if v is not None else "-"

    for name, v in f["fallbacks"].items():
        runs = ", ".join(f"{k} {n}" for k, n in v["runs"].items()) or "-"
        lines.append(f"{name:22s} {v['frames']:6d} {v['fallback_pct']:10.1f} {ms(v['cpu_ms_cheap']):>9s} "
                     f"{ms(v['cpu_ms_fallback']):>11s} {ms(v['cpu_ms_mean']):>8s}  {runs}")
    return "\n".join(lines)
