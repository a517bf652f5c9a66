"""The scoreboard: how lanelib does on every data set at hand, measured in one run, real rows first.

``run`` measures the rows and ``format_table`` prints them as one table (``python -m lanelib
scoreboard``, ``make scoreboard``):

- **CULane dev** (``data.culane_dev``): every listed frame predicted on its own
  (``batch.predict_benchmark``: every line seen, up to two a side) with ``batch.benchmark_config``
  and scored by CULane's official rules (30 px lines on 1640x590, IoU > 0.5): precision, recall, F1.
- **CULane dev, cameras moved**: the same frames and labels moved by whole pixels (``moved_culane``:
  each sequence by the next of ``CAMERA_MOVES``, as another car's camera, pitched or turned a
  little otherwise, sees the road), predicted with the same preset and scored alike: how much a
  camera mounted otherwise than the preset's costs.
- **TuSimple dev** (``data.tusimple_dev``): its 512x288 frames upscaled to 1280x720
  (``upscaled_tusimple``: bicubic, PNG, written once into a cache folder under ``out``), predicted
  and scored on the official 1280x720 rows of its full-resolution labels: accuracy, FP, FN.
- **TuSimple dev, upscaled bilinear**: the same frames upscaled bilinear (``TUSIMPLE_UPSCALES``),
  blurrier, predicted and scored alike: how much the figure owes to the upscale (a frame at
  TuSimple's own resolution is sharper than either, and faint paint such as raised dots is at
  the masks' floors at 512x288).
- **Udacity project and challenge videos** (the highway camera, ``data.udacity_calibration``, the
  default config) and the **P1 clips** ``solidWhiteRight`` and ``solidYellowLeft`` (the ``p1``
  preset, no calibration): tracked through the whole clip as the ``video`` command tracks
  (``track_clip``), nothing written, and scored without labels (``clip_figures``): the share of
  plausible frames (the lane found, ``PLAUSIBLE_WIDTH_M`` wide, within ``PLAUSIBLE_OFFSET_M`` of
  the car's centre) and the first frame from which the lane stays found.
- **Synthetic** rows: samples of ``SYNTH_FRAMES`` frames in the TuSimple and CULane layouts
  (``synth.datasets.write_dataset``: exact labels; the geometry estimated from the frames; the
  built-in settings, since the generator's camera is not the benchmark's) scored as the real ones, and the bundled clip ``videos/project.mp4`` scored against its truth with the
  tracker (``evaluate.evaluate_video``): point accuracy.

Every row runs with OpenCV on one thread. ``ms/frame`` is the mean time of one frame's detection
(the predict rows: ``batch.FrameOutcome.run_time_ms``) or of the ``video`` command's work on one
frame without the codec (the video rows: tracking and drawing). A row whose data is absent is
skipped with the reason (``data.missing_reason``); a row that fails keeps its error and the
others run. Figures are rounded to what they mean: percentages to 0.1, TuSimple's FP and FN to
0.01, times to whole ms.
"""
from __future__ import annotations

import dataclasses
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Callable, NamedTuple, Sequence

import cv2
import numpy as np

from . import autogeometry, batch, data, evaluate, io
from .bench import one_thread
from .benchmarks import culane, tusimple
from .benchmarks.metrics import MAX_RUN_TIME_MS, CULaneCounts, tusimple_f1
from .camera import Calibration
from .config import PipelineConfig, override, preset, preset_names
from .errors import InputError, LaneLibError
from .pipeline import LanePipeline
from .synth.datasets import write_dataset

DEFAULT_OUT = Path("out") / "scoreboard"
PLAUSIBLE_WIDTH_M = (3.0, 4.5)  # a plausible lane's width (US lanes are about 3.7 m)
PLAUSIBLE_OFFSET_M = 0.6        # a plausible car's |offset| from the lane's centre is below this
SYNTH_FRAMES = 10               # frames of each synthetic benchmark sample (one sequence)
TUSIMPLE_SIZE = tusimple.IMAGE_SIZE  # (width, height) of TuSimple's frames and official label rows
TUSIMPLE_CACHE = "tusimple-dev-1280x720"  # under ``out``: the upscaled frames and their labels
# how the TuSimple dev rows upscale the 512x288 frames: (cache folder under ``out``, OpenCV flag)
TUSIMPLE_UPSCALES = {"bicubic": (TUSIMPLE_CACHE, cv2.INTER_CUBIC),
                     "bilinear": (TUSIMPLE_CACHE + "-bilinear", cv2.INTER_LINEAR)}
MOVED_CACHE = "culane-dev-moved"  # under ``out``: the moved CULane frames and their labels
# (dx, dy) px that moved_culane moves the sequences' frames by, in turn: pitched down; turned left and pitched up
CAMERA_MOVES = ((0, 15), (-40, -10))
P1_VIDEOS = {"p1-white": "test_videos/solidWhiteRight.mp4", "p1-yellow": "test_videos/solidYellowLeft.mp4"}

# how each figure prints: its label, and the format of its value
_LABELS = {"precision_pct": "precision", "recall_pct": "recall", "f1_pct": "F1", "tp": "TP",
           "fp": "FP", "fn": "FN", "accuracy_pct": "accuracy", "fp_rate": "FP", "fn_rate": "FN",
           "plausible_pct": "plausible", "found_pct": "found", "first_held_frame": "held from frame",
           "point_accuracy_pct": "point accuracy", "over_200ms": "frames over 200 ms"}


# --------------------------------------------------------------------------- the arithmetic

def pct(fraction: float | None) -> float | None:
    """Return a fraction as a percentage to 0.1 (None for None or NaN).

    Examples
    --------
    >>> pct(0.97536), pct(float("nan"))
    (97.5, None)
    """
    if fraction is None or not np.isfinite(fraction):
        return None
    return round(100.0 * float(fraction), 1)


def detection_figures(tp: int, fp: int, fn: int) -> dict:
    """Return precision, recall and F1 (%, to 0.1) of line counts, and the counts.

    A ratio whose denominator is 0 is 0 (CULane's rule, ``metrics.CULaneCounts``).

    Examples
    --------
    >>> detection_figures(3, 1, 2)
    {'precision_pct': 75.0, 'recall_pct': 60.0, 'f1_pct': 66.7, 'tp': 3, 'fp': 1, 'fn': 2}
    """
    c = CULaneCounts(tp, fp, fn)
    return {"precision_pct": pct(c.precision), "recall_pct": pct(c.recall), "f1_pct": pct(c.f1),
            "tp": tp, "fp": fp, "fn": fn}


def tusimple_figures(accuracy: float, fp: float, fn: float) -> dict:
    """Return TuSimple's accuracy (%, to 0.1), its FP and FN rates (to 0.01) and their F1 (%, to
    0.1: ``metrics.tusimple_f1``).

    Examples
    --------
    >>> tusimple_figures(0.87654, 0.1, 1 / 3)
    {'accuracy_pct': 87.7, 'fp_rate': 0.1, 'fn_rate': 0.33, 'f1_pct': 76.6}
    """
    return {"accuracy_pct": pct(accuracy), "fp_rate": round(float(fp), 2), "fn_rate": round(float(fn), 2),
            "f1_pct": pct(tusimple_f1(fp, fn))}


def plausible(found: Sequence[bool], width_m: Sequence[float], offset_m: Sequence[float]) -> np.ndarray:
    """Return per frame whether the lane is plausible: found, ``PLAUSIBLE_WIDTH_M`` wide (bounds
    included) and less than ``PLAUSIBLE_OFFSET_M`` from the car's centre (NaN is not plausible).

    Examples
    --------
    >>> plausible([True, True, True, False], [3.7, 4.6, 3.0, 3.7], [0.1, 0.1, -0.59, 0.0]).tolist()
    [True, False, True, False]
    """
    w, o = np.asarray(width_m, np.float64), np.asarray(offset_m, np.float64)
    lo, hi = PLAUSIBLE_WIDTH_M
    return np.asarray(found, bool) & (w >= lo) & (w <= hi) & (np.abs(o) < PLAUSIBLE_OFFSET_M)


def first_held_frame(found: Sequence[bool]) -> int | None:
    """Return the first frame from which the lane stays found to the clip's end (None if the
    last frame has no lane, or there is no frame).

    Examples
    --------
    >>> first_held_frame([False, True, False, True, True]), first_held_frame([True, False])
    (3, None)
    """
    lost = np.flatnonzero(~np.asarray(found, bool))
    if len(found) == 0 or (lost.size and lost[-1] == len(found) - 1):
        return None
    return int(lost[-1]) + 1 if lost.size else 0


def clip_figures(found: Sequence[bool], width_m: Sequence[float], offset_m: Sequence[float]) -> dict:
    """Return a tracked clip's plausible and found frames (%, to 0.1) and its first held frame.

    Examples
    --------
    >>> clip_figures([False, True, True, True], [None, 3.7, 5.0, 3.6], [None, 0.2, 0.2, 0.3])
    {'plausible_pct': 50.0, 'found_pct': 75.0, 'first_held_frame': 1}
    """
    ok = plausible(found, np.asarray(width_m, np.float64), np.asarray(offset_m, np.float64))
    n = len(ok)
    return {"plausible_pct": pct(ok.mean()) if n else None,
            "found_pct": pct(np.mean(np.asarray(found, bool))) if n else None,
            "first_held_frame": first_held_frame(found)}


def mean_ms(times_ms: Sequence[float]) -> int | None:
    """Return the mean time per frame in whole ms (None without frames).

    Examples
    --------
    >>> mean_ms([20.4, 21.0, 22.1]), mean_ms([])
    (21, None)
    """
    return int(round(float(np.mean(times_ms)))) if len(times_ms) else None


# --------------------------------------------------------------------------- rows

@dataclass(frozen=True)
class Row:
    """One row of the scoreboard: what was measured, on how many frames, the figures (rounded,
    under the keys of ``_LABELS``), the mean ms per frame, the row's wall time, and either the
    reason it was skipped (its data is absent) or the error it failed with."""

    key: str
    title: str
    source: str = ""
    frames: int | None = None
    figures: dict = field(default_factory=dict)
    ms_per_frame: int | None = None
    seconds: float = 0.0
    skipped: str = ""
    error: str = ""

    def to_dict(self) -> dict:
        """Return the row as JSON-able values."""
        return dataclasses.asdict(self)

    def cells(self) -> tuple[str, str, str, str, str]:
        """Return the printed cells: title, frames, figures (or why not), ms/frame, source."""
        if self.skipped or self.error:
            why = f"skipped: {self.skipped}" if self.skipped else f"failed: {self.error}"
            return self.title, "", why, "", self.source
        shown = ", ".join(_figure(k, v) for k, v in self.figures.items())
        ms = "" if self.ms_per_frame is None else str(self.ms_per_frame)
        return self.title, str(self.frames), shown, ms, self.source


def _figure(key: str, value) -> str:
    label = _LABELS.get(key, key)
    if value is None:
        return f"{label} none"
    if key.endswith("_pct"):
        return f"{label} {value:.1f} %"
    if key.endswith("_rate"):
        return f"{label} {value:.2f}"
    return f"{label} {value}"


class Measured(NamedTuple):
    """What a row's measurement gives: its source, frames, figures and mean ms per frame."""

    source: str
    frames: int
    figures: dict
    ms_per_frame: int | None = None


Settings = Sequence[str]
Measure = Callable[[Path, Settings], Measured]


class _Absent(Exception):
    """A row's data is not here; the message says what was looked for and how to point at it."""


def _need(name: str, sub: str = "") -> Path:
    path = data.dataset(name, sub)
    if path is None:
        raise _Absent(data.missing_reason(sub, name))
    return path


def _config_name(benchmark: str) -> str:
    return f"preset {benchmark}" if benchmark in preset_names() else "default config"


def fresh_folder(folder: Path) -> Path:
    """Return ``folder`` with an earlier run's predictions removed, so that every frame is
    predicted, and timed, in this run; a folder that holds anything else is refused."""
    if folder.is_dir() and any(folder.iterdir()):
        if not (folder / batch.PREDICT_SETTINGS).is_file():
            raise InputError(f"{folder}: holds files that are not predictions of an earlier "
                             "scoreboard; pass another --out folder")
        shutil.rmtree(folder)
    return folder


def _predict(benchmark: str, root: Path, out: Path, list_file: Path | None, config: PipelineConfig,
             auto_geometry: autogeometry.GeometryOptions | None = None) -> batch.PredictRun:
    run = batch.predict_benchmark(benchmark, root, fresh_folder(out), list_file=list_file, config=config,
                                  auto_geometry=auto_geometry, progress=False)
    if run.failed:
        raise InputError(f"{len(run.failed)} of {run.frames} frames failed, the first: {run.failed[0].error}")
    return run


def _predict_ms(run: batch.PredictRun) -> int | None:
    return mean_ms([o.run_time_ms for o in run.outcomes])


def _culane_scored(listed: Path, out: Path, settings: Settings, source: str) -> Measured:
    """Return the CULane frames of ``listed`` (relative to its folder) predicted into ``out`` with
    the culane preset and ``settings``, scored by the official rules; ``source`` names them."""
    run = _predict("culane", listed.parent, out, listed, override(batch.benchmark_config("culane"), settings))
    c = culane.evaluate(listed.parent, listed, run.output).counts
    return Measured(f"{source}; {_config_name('culane')}", c.images, detection_figures(c.tp, c.fp, c.fn),
                    _predict_ms(run))


def _culane_dev(out: Path, settings: Settings) -> Measured:
    listed = _need(data.CULANE_DEV) / data.CULANE_DEV_LIST
    return _culane_scored(listed, out / "culane", settings, str(listed))


def moved_culane(root: str | Path, list_file: str | Path, cache: str | Path,
                 moves: Sequence[tuple[int, int]] = CAMERA_MOVES) -> Path:
    """Return the list file of CULane frames moved as another camera sees them, written under ``cache``.

    The frames of each sequence (``batch.frame_sequence``) of ``list_file``, in list order, move by
    the next (dx, dy) px of ``moves`` (the edge rows and columns repeated into the space left),
    and their labelled points with them (points moved out of the image are left out): for small
    angles a camera pitched or turned otherwise sees the same image moved. The frames are written
    as PNG (lossless) under ``cache``, once (remove ``cache`` to write them again), with their
    labels beside them and the list ``cache/list.txt``; nothing is written under ``root``.
    """
    root, cache = Path(root), Path(cache)
    entries = culane.read_list(list_file)
    sequences = list(dict.fromkeys(batch.frame_sequence("culane", e) for e in entries))
    moved = []
    for entry in entries:
        dx, dy = moves[sequences.index(batch.frame_sequence("culane", entry)) % len(moves)]
        name = str(PurePosixPath(entry).with_suffix(".png"))
        target = cache.joinpath(*PurePosixPath(name.lstrip("/")).parts)
        if not target.is_file():
            image = root.joinpath(*PurePosixPath(entry.lstrip("/")).parts)
            frame = io.read_image(image)
            h, w = frame.shape[:2]
            shifted = cv2.warpAffine(frame, np.float32([[1, 0, dx], [0, 1, dy]]), (w, h),
                                     borderMode=cv2.BORDER_REPLICATE)
            lanes = [lane + (dx, dy) for lane in culane.read_lines(culane.lines_path(root, entry))]
            inside = [lane[(lane[:, 0] >= 0) & (lane[:, 0] <= w) & (lane[:, 1] >= 0) & (lane[:, 1] <= h)]
                      for lane in lanes]
            culane.write_labels(cache, {name: [lane for lane in inside if len(lane) >= 2]}, inputs=[image])
            io.write_image(target, shifted, inputs=[image])
        moved.append(name)
    return culane.write_list(cache / "list.txt", moved)


def _culane_moved(out: Path, settings: Settings) -> Measured:
    root = _need(data.CULANE_DEV)
    listed = moved_culane(root, root / data.CULANE_DEV_LIST, out / MOVED_CACHE)
    moves = ", ".join(f"({dx:+d}, {dy:+d})" for dx, dy in CAMERA_MOVES)
    return _culane_scored(listed, out / "culane-moved", settings,
                          f"{root / data.CULANE_DEV_LIST}, each sequence's frames moved by {moves} px in turn")


def upscaled_tusimple(root: str | Path, cache: str | Path, interpolation: int = cv2.INTER_CUBIC) -> Path:
    """Return the label file of TuSimple frames upscaled to 1280x720, written under ``cache``.

    Each frame of ``root``'s full-resolution labels (``data.TUSIMPLE_DEV_FULLRES``: TuSimple's
    official 1280x720 rows, whose frames ``root`` holds downscaled) is resized to
    ``TUSIMPLE_SIZE`` (``tusimple.full_size`` with ``interpolation``, an OpenCV flag: bicubic by
    default) and written as PNG (lossless) to the same path under ``cache``
    with the suffix ``.png``, once: a frame already there is kept (remove ``cache`` to write them
    again). The labels are written to ``cache/label_data_fullres.json`` with their images named
    so. Every file is written atomically; nothing is written under ``root``.
    """
    root, cache = Path(root), Path(cache)
    source = root / data.TUSIMPLE_DEV_FULLRES
    records = []
    for rec in tusimple.read_labels(source):
        name = PurePosixPath(rec.raw_file.lstrip("/")).with_suffix(".png")
        target = cache.joinpath(*name.parts)
        if not target.is_file():
            image = root.joinpath(*PurePosixPath(rec.raw_file.lstrip("/")).parts)
            big = tusimple.full_size(io.read_image(image), interpolation)
            io.write_image(target, big, inputs=[image])
        records.append(dataclasses.replace(rec, raw_file=str(name)))
    return tusimple.write_labels(cache / data.TUSIMPLE_DEV_FULLRES, records, inputs=[source])


def _tusimple_scored(out: Path, settings: Settings, key: str, upscale: str) -> Measured:
    """Return the TuSimple dev frames upscaled by ``upscale`` (``TUSIMPLE_UPSCALES``), predicted
    under ``out/key`` with the tusimple preset and ``settings`` and scored on the official rows."""
    root = _need(data.TUSIMPLE_DEV)
    cache, interpolation = TUSIMPLE_UPSCALES[upscale]
    labels = upscaled_tusimple(root, out / cache, interpolation)
    run = _predict("tusimple", labels.parent, out / key, labels,
                   override(batch.benchmark_config("tusimple"), settings))
    s = tusimple.evaluate(labels, run.output)
    how = "" if upscale == "bicubic" else f" ({upscale})"
    return Measured(f"{root / data.TUSIMPLE_DEV_FULLRES}, frames upscaled to 1280x720{how}; "
                    f"{_config_name('tusimple')}", s.images,
                    tusimple_figures(s.accuracy, s.fp, s.fn) | _over_time(run), _predict_ms(run))


def _tusimple_dev(out: Path, settings: Settings) -> Measured:
    return _tusimple_scored(out, settings, "tusimple", "bicubic")


def _tusimple_bilinear(out: Path, settings: Settings) -> Measured:
    return _tusimple_scored(out, settings, "tusimple-bilinear", "bilinear")


def _over_time(run: batch.PredictRun) -> dict:
    """Return the frames predicted slower than TuSimple's limit (which score 0 by its rules), as
    ``{"over_200ms": n}``, or nothing when there are none: on a loaded machine the accuracy then
    says more about the load than about the lane finding."""
    slow = sum(o.run_time_ms > MAX_RUN_TIME_MS for o in run.outcomes)
    return {"over_200ms": slow} if slow else {}


class ClipRun(NamedTuple):
    """Per frame of a tracked clip: lane found, its width and offset (m, NaN without), ms taken."""

    found: np.ndarray
    width_m: np.ndarray
    offset_m: np.ndarray
    ms: np.ndarray


def track_clip(path: str | Path, config: PipelineConfig = PipelineConfig(),
               calibration: Calibration | None = None) -> ClipRun:
    """Return the lane of every frame of a clip tracked as the ``video`` command tracks it
    (``batch.lane_video_process``: a fresh ``LaneTracker`` on the first frame, the overlay drawn),
    writing nothing, with the time of each frame's work (ms, decoding excluded)."""
    process, _, _ = batch.lane_video_process(config, calibration, debug=False)
    rows, ms = [], []
    with io.VideoReader(path) as reader:
        fps = reader.info.fps
        for i, frame in enumerate(reader):
            t0 = time.perf_counter()
            _, row, _ = process(frame, i, i / fps)
            ms.append((time.perf_counter() - t0) * 1000.0)
            rows.append((bool(row["found"]), row["lane_width_m"], row["offset_m"]))
    found, width, offset = (np.asarray(c) for c in zip(*rows)) if rows else ((), (), ())
    return ClipRun(np.asarray(found, bool), np.asarray(width, np.float64),
                   np.asarray(offset, np.float64), np.asarray(ms))


def _clip(path: Path, config: PipelineConfig, calibration: Calibration | None, how: str) -> Measured:
    clip = track_clip(path, config, calibration)
    return Measured(f"{path}; {how}", len(clip.found), clip_figures(clip.found, clip.width_m, clip.offset_m),
                    mean_ms(clip.ms))


def _udacity_clip(sub: str) -> Measure:
    def measure(out: Path, settings: Settings) -> Measured:
        path = _need(data.UDACITY_ADVANCED, sub)
        return _clip(path, override(PipelineConfig(), settings), data.udacity_calibration(),
                     "Udacity calibration, default config")
    return measure


def _p1_clip(sub: str) -> Measure:
    def measure(out: Path, settings: Settings) -> Measured:
        return _clip(_need(data.UDACITY_P1, sub), override(preset("p1"), settings), None,
                     "preset p1, no calibration")
    return measure


def _synth_sample(benchmark: str) -> Measure:
    def measure(out: Path, settings: Settings) -> Measured:
        sample = write_dataset(benchmark, out / f"synth-{benchmark}-data", SYNTH_FRAMES, seed=0)
        listed = sample.root / "list" / "test.txt" if benchmark == "culane" else None
        # the generator's camera, not the benchmark's: the built-in settings, not its preset
        run = _predict(benchmark, sample.root, out / f"synth-{benchmark}", listed,
                       override(PipelineConfig(), settings), autogeometry.GeometryOptions())
        if benchmark == "culane":
            c = culane.evaluate(sample.root, listed, run.output).counts
            figures = detection_figures(c.tp, c.fp, c.fn)
        else:
            s = tusimple.evaluate(sample.root, run.output)
            figures = tusimple_figures(s.accuracy, s.fp, s.fn) | _over_time(run)
        return Measured(f"synth dataset {benchmark} --frames {SYNTH_FRAMES} (seed 0, exact labels), "
                        "geometry from the frames; default config", len(sample.images), figures,
                        _predict_ms(run))
    return measure


def _synth_clip(out: Path, settings: Settings) -> Measured:
    path = data.bundled("videos") / "project.mp4"
    camera = evaluate.calibration_from_truth(path)
    pipe = LanePipeline(override(PipelineConfig(), settings), camera, size=camera.image_size)
    s = evaluate.evaluate_video(path, pipe, use_tracker=True, progress=False).summary()
    return Measured(f"{path} against its truth, tracker; default config", s["frames"],
                    {"point_accuracy_pct": pct(s["point_accuracy"]), "found_pct": pct(s["found_rate"])})


# key: (title, measure(out, settings) -> Measured); the real rows first
ROWS: dict[str, tuple[str, Measure]] = {
    "culane": ("CULane dev", _culane_dev),
    "culane-moved": ("CULane dev, cameras moved", _culane_moved),
    "tusimple": ("TuSimple dev", _tusimple_dev),
    "tusimple-bilinear": ("TuSimple dev, upscaled bilinear", _tusimple_bilinear),
    "project": ("Udacity project video", _udacity_clip(data.PROJECT_VIDEO)),
    "challenge": ("Udacity challenge video", _udacity_clip(data.CHALLENGE_VIDEO)),
    "p1-white": ("P1 solidWhiteRight", _p1_clip(P1_VIDEOS["p1-white"])),
    "p1-yellow": ("P1 solidYellowLeft", _p1_clip(P1_VIDEOS["p1-yellow"])),
    "synth-culane": ("synthetic CULane sample", _synth_sample("culane")),
    "synth-tusimple": ("synthetic TuSimple sample", _synth_sample("tusimple")),
    "synth-clip": ("synthetic clip project.mp4", _synth_clip),
}


def select(only: Sequence[str] | None = None) -> list[str]:
    """Return the keys of the rows to run, in the scoreboard's order (all for None).

    Raises ``InputError`` for no key or an unknown one, naming the rows there are.
    """
    if only is None:
        return list(ROWS)
    if not only:
        raise InputError(f"--only: give one row or more of {', '.join(ROWS)}")
    unknown = [k for k in only if k not in ROWS]
    if unknown:
        raise InputError(f"--only {unknown[0]}: no such row; the rows are {', '.join(ROWS)}")
    return [k for k in ROWS if k in only]


def measure_row(key: str, out: Path, settings: Settings = ()) -> Row:
    """Return one row measured, skipped (its data is absent) or failed (a lanelib error); with
    ``settings`` (``config.override``'s ``"part.key=value"``) set on the row's own config."""
    title, measure = ROWS[key]
    t0 = time.perf_counter()
    try:
        m = measure(out, settings)
    except _Absent as e:
        return Row(key, title, skipped=str(e))
    except LaneLibError as e:
        return Row(key, title, error=str(e), seconds=round(time.perf_counter() - t0, 1))
    return Row(key, title, m.source, m.frames, m.figures, m.ms_per_frame, round(time.perf_counter() - t0, 1))


def run(out: str | Path = DEFAULT_OUT, only: Sequence[str] | None = None,
        on_row: Callable[[Row], None] | None = None, settings: Settings = ()) -> list[Row]:
    """Return the scoreboard's rows, each measured in this run with OpenCV on one thread.

    Parameters
    ----------
    out : folder of the run's files: the predictions (``out/<row>/``, replaced every run), the
        synthetic samples and the cache of upscaled TuSimple frames (``upscaled_tusimple``); not
        inside the real data's folder.
    only : the keys of the rows to run (``ROWS``; default all).
    on_row : called with each row as it is done (the CLI prints its progress).
    settings : ``"part.key=value"`` set on every row's config (``config.override``): the row's
        preset or the default config with a part switched (``ablation``).

    Raises
    ------
    InputError
        For an unknown row or an ``out`` inside the real data's folder (before any row runs).
    ConfigError
        For a malformed or unknown setting (before any row runs).
    """
    out = Path(out)
    keys = select(only)
    override(PipelineConfig(), settings)  # a bad setting is refused before any row runs
    if out.resolve().is_relative_to(data.data_root().resolve()):
        raise InputError(f"{out}: is inside the real data's folder {data.data_root()}, which is read in "
                         "place and never written; pass another --out folder")
    rows = []
    with one_thread():
        for key in keys:
            rows.append(measure_row(key, out, settings))
            if on_row is not None:
                on_row(rows[-1])
    return rows


def format_table(rows: Sequence[Row]) -> str:
    """Return the rows as one plain-text table (real rows first, as ``ROWS`` orders them)."""
    head = ("row", "frames", "figures", "ms/frame", "source")
    cells = [head] + [r.cells() for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(4)]
    align = ("<", ">", "<", ">")
    lines = ["  ".join(f"{c[i]:{a}{w}}" for i, (a, w) in enumerate(zip(align, widths))) + f"  {c[4]}"
             for c in cells]
    return "\n".join(line.rstrip() for line in lines)
