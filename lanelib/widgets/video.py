"""``VideoTuner``: the lane tracker's parameters on a clip, with the debug composite of the tracked
frame, a strip of the per-frame confidence and offset, and the tuned video played inline."""
from __future__ import annotations

import math
import os
from dataclasses import replace
from pathlib import Path
from typing import Mapping

import cv2
import ipywidgets as widgets
import numpy as np

from .. import io
from ..batch.video import VideoWriter
from ..camera import Calibration
from ..config import PipelineConfig
from ..data import repo_root
from ..draw import sheet
from ..errors import InputError
from ..pipeline import LanePipeline
from ..result import FrameResult
from ..tracking import LaneTracker
from .base import Tuner, row, sized
from .choices import is_video, picker_items, video_choices
from .strip import STRIP_SIZE_PX, ClipSeries, clip_readout, draw_strip, strip_x_of

DEFAULT_MAX_FRAMES = 125  # 5 s at 25 fps


class TunedVideo(widgets.Video):
    """An ``ipywidgets.Video`` of a written clip whose text form is short and stable (for nbval)."""

    def __init__(self, path: Path, frames: int, **kwargs):
        super().__init__(**kwargs)
        self.path = Path(path)
        self.frames = int(frames)

    def __repr__(self) -> str:
        return f"TunedVideo({self.path.name!r}, frames={self.frames})"

    def _repr_mimebundle_(self, **kwargs) -> dict:
        bundle = dict(super()._repr_mimebundle_(**kwargs) or {})
        bundle["text/plain"] = repr(self)
        return bundle


def played_frames(tracked: int, seconds: float | None, fps: float) -> int:
    """Return how many of ``tracked`` frames ``VideoTuner.play(seconds=...)`` writes (all for None)."""
    if seconds is None:
        return tracked
    if isinstance(seconds, bool) or not isinstance(seconds, (int, float, np.integer, np.floating)) \
            or not math.isfinite(seconds) or seconds <= 0:
        raise InputError(f"VideoTuner.play: seconds={seconds!r}; pass a number of seconds > 0, or None "
                         "for every tracked frame")
    return max(1, min(tracked, round(float(seconds) * fps)))


def played_size(shape: tuple[int, ...], width_px: int | None) -> tuple[int, int] | None:
    """Return the (w, h) ``VideoTuner.play(width_px=...)`` scales frames of ``shape`` to (both even,
    the height keeping the aspect ratio), or None for their own size."""
    if width_px is None:
        return None
    if isinstance(width_px, bool) or not isinstance(width_px, (int, np.integer)) or width_px < 16:
        raise InputError(f"VideoTuner.play: width_px={width_px!r}; pass a whole number of pixels >= 16, "
                         "or None for the clip's size")
    h, w = shape[:2]
    even = int(width_px) // 2 * 2
    return even, max(2, int(even * h / w) // 2 * 2)


class VideoTuner(Tuner):
    """Tune the lane tracker on a clip: its parameters, the tracked frame and the clip at a glance.

    Parameters
    ----------
    images : label -> video path for the picker (default: ``video_choices()``, the bundled
        videos); every item must be a video (an image raises ``InputError``).
    max_frames : frames tracked from the start of the clip (the ``max_frames`` slider; default
        125, 5 s at 25 fps). They are decoded once per clip and kept in memory (2.8 MB a
        1280x720 frame).
    config, calibration, image, tile_width_px, jpeg_quality : as for ``Tuner``.

    Sliders ``tracking.smooth_frames``, ``tracking.recency_decay``, ``tracking.hold_frames``,
    ``tracking.max_jump_m``, ``tracking.base_history_frames`` (0: off),
    ``tracking.min_base_peak``, ``tracking.trend_frames`` (0: off), ``tracking.blind_hold_frames``
    and ``tracking.max_gap_m`` (``TrackerConfig``), ``checks.width_m`` (``min_width_m`` ..
    ``max_width_m`` of ``LaneChecks``) and ``max_frames``. A change re-runs ``LaneTracker`` over
    the cached frames (``results``: one ``FrameResult`` per frame); the frame slider only picks
    which tracked frame is shown, without re-running it (``runs`` counts the runs). The preview
    is the debug composite of the tracked frame (its mask is thresholded again for the view: the
    search saw the same pixels) above a strip of the per-frame confidences and offset
    (``strip``). ``play()`` writes the tracked frames as an annotated video and returns it as a
    playable widget (``play(seconds=2, width_px=640)``: a short, small clip). ``save`` writes the
    ``tracking`` and ``checks`` parts.
    """

    columns = 1
    default_tile_width_px = 800
    parts = ("tracking", "checks")
    shows = ("tracking", "checks")

    def __init__(self, images: Mapping[str, str | os.PathLike] | str | os.PathLike | None = None,
                 config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                 image: str | None = None, max_frames: int = DEFAULT_MAX_FRAMES,
                 tile_width_px: int | None = None, jpeg_quality: int = 80):
        items = picker_items(images, video_choices)
        not_videos = [f"{k} ({v.name})" for k, v in items.items() if not is_video(v)]
        if not_videos:
            more = f" and {len(not_videos) - 5} more" if len(not_videos) > 5 else ""
            raise InputError(f"VideoTuner: {', '.join(not_videos[:5])}{more} not a video; the "
                             f"tracker needs a clip: pass video files ({', '.join(io.VIDEO_SUFFIXES)}), "
                             "e.g. video_choices()")
        if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)) or max_frames < 1:
            raise InputError(f"VideoTuner: max_frames={max_frames!r}; pass a whole number of frames >= 1")
        self._max_frames = int(max_frames)
        self._clip: tuple[Path | None, list[np.ndarray], bool] = (None, [], False)  # path, frames, whole clip
        self._calibration: Calibration | None = None
        self.results: list[FrameResult] = []
        self.series: ClipSeries | None = None
        self.runs = 0
        self.composite = np.zeros((0, 0, 3), np.uint8)
        super().__init__(items, config, calibration, image, tile_width_px, jpeg_quality)

    # ---- public ---------------------------------------------------------------------------

    @property
    def max_frames(self) -> int:
        """Frames tracked from the start of the clip (what the ``max_frames`` slider says)."""
        return int(self.controls["max_frames"].value)

    @property
    def frames(self) -> list[np.ndarray]:
        """The tracked frames of the picked clip (RGB, decoded once)."""
        return self._clip[1][:len(self.results)]

    @property
    def frame(self) -> int:
        """Index of the tracked frame shown; setting it shows that frame (no new tracker run)."""
        return int(self.frame_slider.value)

    @frame.setter
    def frame(self, index: int) -> None:
        n = len(self.results)
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < n:
            raise InputError(f"{self.images[self.image]}: frame {index!r} is outside the tracked "
                             f"frames (0..{n - 1}); pass an index in that range, or raise max_frames")
        self.frame_slider.value = int(index)

    def strip(self, size_px: tuple[int, int] = STRIP_SIZE_PX) -> np.ndarray:
        """Return the strip of the run (``strip.draw_strip``): confidences and offset per frame,
        the shown frame marked; RGB uint8 of ``size_px`` (w, h)."""
        return draw_strip(self.series, self.frame, size_px)

    def strip_x(self, frame: int, width_px: int = STRIP_SIZE_PX[0]) -> int:
        """Return the x (px) of ``frame`` in a strip ``width_px`` wide."""
        return strip_x_of(len(self.results), width_px)(frame)

    def preview_sheet(self) -> np.ndarray:
        """Return the preview: the tracked frame's debug composite above the strip, one width."""
        views = self.render()
        name = next(iter(views))
        top = sheet({name: views[name]}, self.tile_width_px, 1)
        strip = views["over the clip"]
        w = top.shape[1]
        strip = cv2.resize(strip, (w, max(1, round(w * strip.shape[0] / strip.shape[1]))),
                           interpolation=cv2.INTER_AREA)
        return np.vstack([top, strip])

    def play(self, path: str | os.PathLike | None = None, seconds: float | None = None,
             width_px: int | None = None) -> TunedVideo:
        """Write the tracked frames annotated with the tuned lane; return the video as a widget.

        The frames and lanes are those of the last run (``results``), drawn as ``python -m
        lanelib video`` draws them (``LanePipeline.annotate`` on the RAW frame, or on the
        undistorted one with ``config.draw.video_undistorted``), at the clip's frame rate.
        ``path`` defaults to ``out/<clip>_tuned.mp4`` in the repository; it is written
        atomically and never over the clip. ``seconds`` keeps only the first seconds of the
        tracked frames and ``width_px`` scales them to that width (the height keeps the aspect
        ratio; both are rounded down to even, as H.264 needs). The widget carries the whole file
        in the notebook, so a short, small clip keeps a saved notebook small. By default every
        tracked frame at the clip's size.
        Returns an ``ipywidgets.Video`` that plays inline.
        """
        clip = self.images[self.image]
        target = Path(path) if path is not None else repo_root() / "out" / f"{clip.stem}_tuned.mp4"
        if target.suffix.lower() not in io.VIDEO_SUFFIXES:
            raise InputError(f"{target}: the output video needs a video suffix "
                             f"({', '.join(io.VIDEO_SUFFIXES)}); e.g. tuned.mp4")
        fps = self._video_info(clip).fps
        n = played_frames(len(self.results), seconds, fps)
        size = played_size(self._clip[1][0].shape, width_px)
        with VideoWriter(target, fps, inputs=[clip]) as writer:
            for frame, result in zip(self.frames[:n], self.results[:n]):
                out = self._annotate(frame, result)
                if size is not None:
                    out = cv2.resize(out, size, interpolation=cv2.INTER_AREA)
                writer.write(out)
        return TunedVideo(target, n, value=target.read_bytes(), format="mp4",
                          autoplay=False, loop=False, controls=True,
                          layout=widgets.Layout(max_width="100%"))

    def annotated(self) -> np.ndarray:
        """Return the tracked frame shown, annotated as ``python -m lanelib video`` draws it.

        The tracker's result for the frame (tracked from the clip's first frame), drawn as
        ``play()`` and ``batch.process_video`` draw it: the frame of the output video before it
        is encoded (``export`` writes it as a lossless PNG).
        """
        i = min(self.frame, len(self.results) - 1)
        return self._annotate(self._clip[1][i], self.results[i])

    def _annotate(self, frame: np.ndarray, result: FrameResult) -> np.ndarray:
        """Return ``frame`` with ``result``'s lane drawn as the video command draws it."""
        pipe = self.pipeline
        if self.config.draw.video_undistorted:
            return pipe.annotate(pipe.undistort(frame), result)
        return pipe.annotate(frame, result, raw=True)

    # ---- hooks ----------------------------------------------------------------------------

    def _build(self) -> list[widgets.Widget]:
        tc, cc = self.config.tracking, self.config.checks
        c = self._control
        made = [
            c("tracking.smooth_frames", widgets.IntSlider(value=tc.smooth_frames, min=1, max=30,
                                                           description="smooth_frames", **sized(380, 130))),
            c("tracking.recency_decay", widgets.FloatSlider(value=tc.recency_decay, min=0.05, max=1.0,
                                                             step=0.05, description="recency_decay",
                                                             **sized(380, 130))),
            c("tracking.hold_frames", widgets.IntSlider(value=tc.hold_frames, min=0, max=60,
                                                         description="hold_frames", **sized(380, 130))),
            c("tracking.max_jump_m", widgets.FloatSlider(value=tc.max_jump_m, min=0.05, max=2.0, step=0.05,
                                                          description="max_jump_m", **sized(380, 130))),
            c("tracking.base_history_frames", widgets.IntSlider(
                value=tc.base_history_frames, min=0, max=100, description="base_history_frames",
                **sized(380, 130))),
            c("tracking.min_base_peak", widgets.FloatSlider(
                value=tc.min_base_peak, min=0.0, max=20.0, step=0.5, description="min_base_peak",
                **sized(380, 130))),
            c("tracking.trend_frames", widgets.IntSlider(value=tc.trend_frames, min=0, max=15,
                                                          description="trend_frames", **sized(380, 130))),
            c("tracking.blind_hold_frames", widgets.IntSlider(
                value=tc.blind_hold_frames, min=0, max=60, description="blind_hold_frames",
                **sized(380, 130))),
            c("tracking.max_gap_m", widgets.FloatSlider(value=tc.max_gap_m, min=3.0, max=60.0, step=1.0,
                                                         description="max_gap_m", **sized(380, 130))),
            c("checks.width_m", widgets.FloatRangeSlider(value=(cc.min_width_m, cc.max_width_m), min=1.0,
                                                          max=6.0, step=0.05, description="width_m",
                                                          **sized(380, 130))),
            c("max_frames", widgets.IntSlider(value=self._max_frames, min=1, max=self._max_frames,
                                              description="max_frames", continuous_update=False,
                                              **sized(380, 130))),
        ]
        for w in made:
            w.continuous_update = False
        return [row(*made[:2]), row(*made[2:4]), row(*made[4:6]), row(*made[6:8]), row(*made[8:10]),
                row(*made[10:])]

    def _sync(self) -> None:
        tc, cc = self.config.tracking, self.config.checks
        for k in ("smooth_frames", "recency_decay", "hold_frames", "max_jump_m", "base_history_frames",
                  "min_base_peak", "trend_frames", "blind_hold_frames", "max_gap_m"):
            self.controls[f"tracking.{k}"].value = getattr(tc, k)
        self.controls["checks.width_m"].value = (cc.min_width_m, cc.max_width_m)

    def _apply(self, key: str) -> PipelineConfig:
        cfg = self.config
        ctl = self.controls
        tracking = replace(cfg.tracking,
                           smooth_frames=int(ctl["tracking.smooth_frames"].value),
                           recency_decay=round(float(ctl["tracking.recency_decay"].value), 3),
                           hold_frames=int(ctl["tracking.hold_frames"].value),
                           max_jump_m=round(float(ctl["tracking.max_jump_m"].value), 3),
                           base_history_frames=int(ctl["tracking.base_history_frames"].value),
                           min_base_peak=round(float(ctl["tracking.min_base_peak"].value), 3),
                           trend_frames=int(ctl["tracking.trend_frames"].value),
                           blind_hold_frames=int(ctl["tracking.blind_hold_frames"].value),
                           max_gap_m=round(float(ctl["tracking.max_gap_m"].value), 3))
        lo, hi = ctl["checks.width_m"].value
        checks = replace(cfg.checks, min_width_m=round(float(lo), 3), max_width_m=round(float(hi), 3))
        return replace(cfg, tracking=tracking, checks=checks)

    def _prepare(self, raw: np.ndarray, calibration: Calibration | None) -> None:
        self._calibration = calibration
        n = self._video_info(self.images[self.image]).n_frames
        with self._quiet():  # the clip's length bounds max_frames
            self.controls["max_frames"].max = max(1, n)

    def _update(self, key: str | None) -> None:
        """Re-run the tracker over the cached frames when its inputs changed; show the frame."""
        path = self.images[self.image]
        frames = self._decode(path, self.max_frames)
        size = (frames[0].shape[1], frames[0].shape[0])
        cfg = self.config
        pkey = (id(self._calibration), size, cfg.perspective, cfg.thresholds, cfg.search, cfg.draw)
        self.pipeline = self._cached("pipeline", pkey,
                                     lambda: LanePipeline(cfg, self._calibration, size=size))
        run_key = (pkey, cfg.tracking, cfg.checks, path, len(frames))
        self.results = self._cached("run", run_key, lambda: self._track(frames))
        self.series = self._cached("series", run_key, lambda: ClipSeries.of(self.results))
        with self._quiet():
            self.frame_slider.max = len(self.results) - 1
        self._show_frame()

    def render(self) -> dict[str, np.ndarray | None]:
        """Return the debug composite of the tracked frame shown and the strip over the clip."""
        r = self.results[self.frame]
        return {f"frame {self.frame}: tracked ({r.method})": self.composite,
                "over the clip": self.strip()}

    def readout(self) -> str:
        """Return the run's figures and the shown frame's (``strip.clip_readout``)."""
        if self.series is None or not self.results:
            return ""
        return clip_readout(self.series, self.results, self.frame, self._video_info(self.images[self.image]).fps)

    # ---- wiring ---------------------------------------------------------------------------

    def _on_frame(self, change) -> None:
        # a frame is not a setting: show the tracked frame, the tracker is not re-run
        if not self._syncing and self.results:
            self._show_frame()
            self._refresh()

    def _decode(self, path: Path, n: int) -> list[np.ndarray]:
        """Return the first ``n`` frames of ``path`` (fewer if the clip is shorter), decoded once.

        One clip is kept: picking another drops the frames of the last. Asking for more frames
        than were decoded reads the clip again from its start.
        """
        held_path, frames, whole = self._clip
        if held_path != path or (len(frames) < n and not whole):
            frames = []
            with io.VideoReader(path) as reader:
                for frame in reader:
                    frames.append(frame)
                    if len(frames) == n:
                        break
            whole = len(frames) < n  # the clip ended first
            self._clip = (path, frames, whole)
        return frames[:n]

    def _track(self, frames: list[np.ndarray]) -> list[FrameResult]:
        """Return the tracker's result for each frame, in order, from a fresh tracker."""
        tracker = LaneTracker(self.pipeline, self.config.tracking, self.config.checks)
        results = [tracker.update(f) for f in frames]
        self.runs += 1
        return results

    def _show_frame(self) -> None:
        """Make the debug composite of the tracked frame the slider shows."""
        i = min(self.frame, len(self.results) - 1)
        raw = self._clip[1][i]
        self._raw = raw
        pipe = self.pipeline
        bird = pipe.birdseye(raw)
        # the whole view's mask: the band-only search of a tracked frame saw the same pixels
        result = replace(self.results[i], images={"birdseye": bird, "binary": pipe.binary(bird)})
        self.composite = pipe.debug_composite(result, raw=raw)
