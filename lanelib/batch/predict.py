"""Predictions on a benchmark's labelled frames (``predict``): each frame detected on its own and
written in the benchmark's format (TuSimple, CULane), resumable, in one process or on Dask.
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Callable, Sequence

import numpy as np
from tqdm import tqdm

from .. import cluster, io
from ..autogeometry import GeometryOptions, RoadGeometry, low_confidence
from ..benchmarks import culane, tusimple, written
from ..camera import Calibration
from ..config import PipelineConfig, preset, preset_names, to_dict
from ..errors import ConfigError, GeometryError, InputError, LaneLibError, naming_the_file
from ..lines.result import LinesResult
from ..pipeline import LanePipeline
from .geometry import with_geometry
from .refine import PointsRefinement, sequence_refinement, shifted_points


PREDICT_BENCHMARKS = ("tusimple", "culane")
TUSIMPLE_PREDICTIONS = "predictions.json"  # PRED_DIR/predictions.json: the TuSimple prediction file
TUSIMPLE_PARTS = "parts"                   # PRED_DIR/parts/<raw_file>.json: one JSON line per frame
PREDICT_SETTINGS = "predict.json"          # PRED_DIR/predict.json: what the predictions were made with
PREDICT_FORMAT = "lanelib-predict/1"


# pipelines predict_frame keeps in its cache: the last few sequences'
PIPELINES_KEPT = 4


@dataclass(frozen=True)
class FrameWork:
    """One labelled frame to predict: all a worker needs besides the sequence's config.

    Parameters
    ----------
    benchmark : "tusimple" or "culane".
    name : the frame as the labels name it (TuSimple ``raw_file``, CULane list entry).
    image : the image file.
    sequence : the camera's folder (``frame_sequence``); its frames share one autogeometry.
    rows_px : the rows the lanes are given at (TuSimple: the label's ``h_samples``; CULane:
        ``culane.SAMPLE_ROWS_PX``, bottom up).
    target : the frame's own prediction file (TuSimple: a part; CULane: its ``.lines.txt``).
    """

    benchmark: str
    name: str
    image: Path
    sequence: str
    rows_px: tuple[float, ...]
    target: Path


@dataclass(frozen=True)
class FrameOutcome:
    """What ``predict_frame`` did with one frame: lines written, time (ms), or the error."""

    name: str
    lines: int = 0
    run_time_ms: float = 0.0
    error: str = ""


@dataclass(frozen=True)
class GeometryFallback:
    """A sequence of a ``predict_benchmark`` run whose geometry estimate was not used: its frames
    keep the bird's-eye points of the run's config. ``reason`` says why (the frames give no
    consistent vanishing point, none could be read, or the confidence is too low)."""

    sequence: str
    reason: str

    def note(self, points_of: str) -> str:
        """Return the one-line note of this fallback; ``points_of`` names the config, e.g.
        ``"the tusimple preset"``.

        Examples
        --------
        >>> GeometryFallback("clips/0313-1", "no road").note("the tusimple preset")
        "clips/0313-1: road geometry not used (no road); its frames use the tusimple preset's bird's-eye points"
        """
        return (f"{self.sequence}: road geometry not used ({self.reason}); its frames use {points_of}'s "
                "bird's-eye points")


@dataclass(frozen=True)
class PredictRun:
    """What ``predict_benchmark`` did: frames listed, skipped (predicted before), predicted, failed.

    ``outcomes`` holds the frames run now, in list order; ``output`` is the prediction file
    (TuSimple) or folder (CULane) to pass to ``evaluate``; ``geometries`` the road geometry of each
    sequence whose estimate is used (``--auto-geometry``), ``fallbacks`` the sequences whose
    estimate was refused or failed (they keep the config's points), ``refinements`` what
    ``lines.refine_points_px`` did with each sequence's points, all in list order.
    """

    frames: int
    skipped: int
    outcomes: tuple[FrameOutcome, ...]
    output: Path
    seconds: float
    geometries: tuple[tuple[str, RoadGeometry], ...] = ()
    fallbacks: tuple[GeometryFallback, ...] = ()
    refinements: tuple[PointsRefinement, ...] = ()

    @property
    def failed(self) -> tuple[FrameOutcome, ...]:
        return tuple(o for o in self.outcomes if o.error)

    @property
    def without_lines(self) -> int:
        """Return how many frames run now found no line (an empty prediction was written)."""
        return sum(1 for o in self.outcomes if not o.error and o.lines == 0)


def benchmark_config(benchmark: str) -> PipelineConfig:
    """Return the config a benchmark's frames are predicted with by default: the bundled preset named
    like it (``tusimple``, ``culane``: its fixed camera), else the built-in one; frames of another
    size get its points scaled (``pipeline.LanePipeline``).

    Examples
    --------
    >>> benchmark_config("no such benchmark") == PipelineConfig()
    True
    """
    return preset(benchmark) if benchmark in preset_names() else PipelineConfig()


def frame_sequence(benchmark: str, name: str) -> str:
    """Return the sequence (one camera's folder) of a frame: TuSimple ``clips/0313-1`` of
    ``clips/0313-1/6040/20.jpg`` (the clip's parent), CULane ``driver_23_30frame/05151640_0419.MP4``
    of ``/driver_23_30frame/05151640_0419.MP4/00000.jpg`` (the image's folder)."""
    parts = PurePosixPath(name.lstrip("/")).parts[:-1]
    if benchmark == "tusimple" and len(parts) > 1:
        parts = parts[:-1]
    return "/".join(parts) or "."


def benchmark_work(benchmark: str, root: str | os.PathLike, out_dir: str | os.PathLike,
                   list_file: str | os.PathLike | None = None) -> list[FrameWork]:
    """Return the frames of a benchmark's dataset to predict, in list order.

    Parameters
    ----------
    benchmark : "tusimple" (labels: ``list_file``, a label file, or the label files of ``root``,
        ``tusimple.label_files``: every ``label_data*.json``, else ``test_label*.json``, else the
        test set's task file ``test_tasks*.json``) or "culane" (``list_file``, default
        ``culane.default_list``: ``root/list/test.txt``, else ``root/list.txt``).
    root : the dataset root the labels' image paths are relative to.
    out_dir : the prediction folder (``PRED_DIR``); each frame's target lies under it.

    Raises
    ------
    InputError
        If the root is missing, the labels or the list are bad, an image is missing (naming the
        entry and the file looked for), or ``out_dir`` is the dataset root.
    """
    if benchmark not in PREDICT_BENCHMARKS:
        raise InputError(f"{benchmark!r}: not a benchmark; choose one of {', '.join(PREDICT_BENCHMARKS)}")
    r, out = Path(root), Path(out_dir)
    if not r.is_dir():
        raise InputError(f"{r}: no such folder; pass the {benchmark} dataset root (the folder the "
                         "labels' image paths are relative to)")
    if out.resolve() == r.resolve():
        raise InputError(f"{out}: the prediction folder is the dataset root (predictions would lie "
                         "among the labels); choose another -o folder")
    if benchmark == "tusimple":
        labels = Path(list_file) if list_file is not None else r
        source = str(labels)
        named = [(rec.raw_file, tuple(rec.h_samples)) for rec in tusimple.read_labels(labels, tasks=True)]
    else:
        source = str(Path(list_file) if list_file is not None else culane.default_list(r))
        named = [(entry, culane.SAMPLE_ROWS_PX) for entry in culane.read_list(source)]
    work = []
    for n, (name, rows) in enumerate(named, 1):
        image = r.joinpath(*PurePosixPath(name.lstrip("/")).parts)
        if not image.is_file():
            raise InputError(f"{source}: entry {n} ({name}) has no image: {image} is missing; pass the "
                             "dataset root the labels are relative to, or a list of the images you have")
        if benchmark == "tusimple":
            target = out.joinpath(TUSIMPLE_PARTS, *PurePosixPath(name.lstrip("/")).with_suffix(".json").parts)
        else:
            target = culane.lines_path(out, name)
        work.append(FrameWork(benchmark, name, image, frame_sequence(benchmark, name),
                              tuple(float(y) for y in rows), target))
    return work


def seen_lines(found: LinesResult, rows_px: Sequence[float], w: int,
               benchmark: str | None = None) -> list[np.ndarray]:
    """Return the x (px) at ``rows_px`` of every line ``detect_lines`` saw, left to right.

    x is NaN on rows where the line is not seen or outside the image (``w`` px wide); a line
    with fewer than 2 points is left out. ``benchmark``: only the lines it labels
    (``benchmarks.written``), else all.
    """
    kept = written(benchmark, list(found.lines))
    out = []
    for line in kept:
        xs = line.x_at_rows(rows_px)
        xs[~((xs >= 0) & (xs <= w - 1))] = np.nan
        if np.count_nonzero(np.isfinite(xs)) >= 2:
            out.append(xs)
    return out


def _prediction_text(work: FrameWork, lines: list[np.ndarray], run_time_ms: float) -> str:
    """Return the text of a frame's prediction file in its benchmark's format."""
    rows = np.asarray(work.rows_px, np.float64)
    if work.benchmark == "tusimple":
        lanes = tuple(tuple(tusimple.NO_POINT if not math.isfinite(x) else round(float(x), 2) for x in xs)
                      for xs in lines)
        record = tusimple.TuSimpleRecord(work.name, lanes, work.rows_px, round(run_time_ms, 1))
        return tusimple.record_line(record, work.target, prediction=True)
    pts = [np.column_stack([np.round(xs[np.isfinite(xs)], 2), rows[np.isfinite(xs)]]) for xs in lines]
    return culane.format_lines(pts)


def predict_frame(work: FrameWork, config: PipelineConfig, calibration: Calibration | None,
                  cache: dict) -> FrameOutcome:
    """Return the outcome of detecting the lane in one frame on its own and writing its prediction.

    The frame is read, ``LanePipeline.detect_lines`` runs on it (no prior: each labelled frame
    stands alone), every line seen is sampled at ``work.rows_px`` where it is seen (``seen_lines``;
    the lines the benchmark labels, ``benchmarks.written``) and written to
    ``work.target`` atomically (a frame with no line found gets an empty prediction); stale
    temporaries of that target from a killed run are removed first. ``run_time_ms`` is the
    detection and sampling time. ``cache`` keeps one pipeline per (sequence, frame size) across
    calls (a worker's own dict), the last ``PIPELINES_KEPT`` of them (each holds its maps, so a
    run's memory stays bounded however many sequences it lists). A lanelib error
    (unreadable image, a size the calibration does not fit) is the outcome's ``error``; a
    ``ConfigError`` is raised (it fails every frame).
    """
    try:
        rgb = io.read_image(work.image)
        key = (work.sequence, rgb.shape[1], rgb.shape[0])
        if key not in cache:
            while len(cache) >= PIPELINES_KEPT:  # the oldest goes: lists run sequence by sequence
                del cache[next(iter(cache))]
            cache[key] = LanePipeline(config, calibration, size=key[1:])
            cache[key].lines_view()  # per camera, like the pipeline's own maps: not in run_time
        pipe = cache[key]
        t0 = time.perf_counter()
        lines = seen_lines(pipe.detect_lines(rgb, ego=False), work.rows_px, w=rgb.shape[1],
                           benchmark=work.benchmark)
        ms = (time.perf_counter() - t0) * 1000.0
        io.remove_stale_temp_files(work.target)
        io.write_text(work.target, _prediction_text(work, lines, ms), inputs=[work.image])
    except ConfigError:
        raise
    except LaneLibError as e:
        return FrameOutcome(work.name, error=naming_the_file(str(e), work.image))
    return FrameOutcome(work.name, len(lines), ms)


def predict_chunk(chunk: Sequence[FrameWork], configs: dict[str, PipelineConfig],
                  calibration: Calibration | None) -> list[FrameOutcome]:
    """Return the outcome of ``predict_frame`` for each frame of a chunk, in order (a Dask task).

    ``configs`` holds the config of each sequence of the chunk (its geometry estimated by the
    client); the pipelines are built once per chunk and sequence.
    """
    cache: dict = {}
    return [predict_frame(w, configs[w.sequence], calibration, cache) for w in chunk]


def _check_visible(outcomes: list[FrameOutcome], work: Sequence[FrameWork]) -> list[FrameOutcome]:
    """Return the outcomes, a frame a worker wrote where this process does not see it failed."""
    checked = []
    for o, w in zip(outcomes, work):
        if not o.error and not w.target.is_file():
            o = FrameOutcome(o.name, error=f"{w.target}: a Dask worker wrote this prediction but it is "
                                           "not here; --scheduler needs the dataset and PRED_DIR on a "
                                           "filesystem every worker sees at the same path")
        checked.append(o)
    return checked


def _settings(benchmark: str, root: Path, config: PipelineConfig, calibration_file: str | None,
              auto_geometry: GeometryOptions | None) -> dict:
    return {"format": PREDICT_FORMAT, "benchmark": benchmark, "dataset_root": str(root.resolve()),
            "calibration": calibration_file, "config": to_dict(config),
            "auto_geometry": to_dict(auto_geometry) if auto_geometry is not None else None}


def _check_settings(out: Path, settings: dict) -> bool:
    """Return whether ``out`` records these settings already; raise if it records others."""
    path = out / PREDICT_SETTINGS
    if not path.is_file():
        return False
    old = io.read_json(path, "prediction settings file")
    if old != settings:
        keys = sorted(k for k in set(old) | set(settings) if old.get(k) != settings.get(k))
        raise InputError(f"{out}: holds predictions made with other settings ({', '.join(keys)} "
                         f"differ; see {path}); pass another -o folder, or remove it to start again")
    return True


def _record_settings(out: Path, settings: dict) -> None:
    """Write ``out/predict.json``, the settings record (``_check_settings`` reads it)."""
    path = out / PREDICT_SETTINGS
    io.remove_stale_temp_files(path)
    io.write_json(path, settings)


def _sequence_geometry(work: Sequence[FrameWork], calibration: Calibration | None,
                       options: GeometryOptions) -> RoadGeometry | GeometryFallback:
    """Return the geometry of one sequence, estimated from up to ``options.max_frames`` of its
    frames, evenly spread, or a ``GeometryFallback`` saying why it is not used: the estimate
    failed (``GeometryError``, or frames it cannot take) or its confidence is below
    ``autogeometry.LOW_CONFIDENCE`` without ``options.accept_low_confidence``. A value, not an
    exception, so that a Dask task returns it like a geometry. An image that cannot be read is
    left out here (``predict_frame`` reports it)."""
    step = max(1, math.ceil(len(work) / options.max_frames))
    frames = []
    for w in work[::step]:
        try:
            frames.append(io.read_image(w.image))
        except InputError:
            continue
    sequence = work[0].sequence
    if not frames:
        return GeometryFallback(sequence, "none of its images could be read")
    try:
        # one calibration serves every sequence's frames: no lens is estimated per sequence
        geo = options.estimate(frames, calibration, lens_from_road=False)
    except (GeometryError, InputError) as e:
        return GeometryFallback(sequence, str(e))
    if geo.low_confidence and not options.accept_low_confidence:
        return GeometryFallback(sequence, f"{low_confidence(geo, len(frames))}; --accept-low-confidence "
                                          "uses it")
    return geo


def _assemble_tusimple(work: Sequence[FrameWork], out: Path, inputs: Sequence[Path]) -> Path:
    """Write ``PRED_DIR/predictions.json`` from the parts of the listed frames that have one."""
    records = []
    for w in work:
        if w.target.is_file():
            text = w.target.read_text(encoding="utf-8")
            records.append(tusimple.parse_record(text, str(w.target), prediction=True))
    path = out / TUSIMPLE_PREDICTIONS
    io.remove_stale_temp_files(path)
    return tusimple.write_predictions(path, records, inputs=inputs)


def _sequence_configs(work: Sequence[FrameWork], sequences: Sequence[str], config: PipelineConfig,
                      calibration: Calibration | None, options: GeometryOptions, client,
                      on_geometry: Callable[[str, RoadGeometry | GeometryFallback], None] | None
                      ) -> tuple[dict[str, PipelineConfig], list[tuple[str, RoadGeometry]], list[GeometryFallback]]:
    """Return the config of each of ``sequences`` (``config`` with its estimated geometry, or
    ``config`` itself where the estimate is not used), the geometries used and the fallbacks.

    The estimates run here, or on the Dask ``client``'s workers, one task per sequence.
    """
    groups = [[w for w in work if w.sequence == sequence] for sequence in sequences]
    if client is None:
        estimates = (_sequence_geometry(g, calibration, options) for g in groups)
    else:  # one task per sequence, all sent at once; results in order
        estimates = cluster.map_ordered(client, _sequence_geometry, groups, calibration=calibration,
                                        options=options)
    configs, geometries, fallbacks = {}, [], []
    for sequence, estimate in zip(sequences, estimates):
        if on_geometry is not None:
            on_geometry(sequence, estimate)
        if isinstance(estimate, GeometryFallback):
            fallbacks.append(estimate)
            configs[sequence] = config
        else:
            geometries.append((sequence, estimate))
            configs[sequence] = with_geometry(config, estimate)
    return configs, geometries, fallbacks


def _sequence_setup(work: Sequence[FrameWork], sequences: Sequence[str], config: PipelineConfig,
                    calibration: Calibration | None, auto_geometry: GeometryOptions | None, client,
                    on_geometry: Callable[[str, RoadGeometry | GeometryFallback], None] | None,
                    on_points: Callable[[PointsRefinement], None] | None) -> tuple:
    """Return the config of each of ``sequences``, the geometries used, the fallbacks and the
    refinements: ``config`` with each sequence's geometry estimate (``auto_geometry``,
    ``_sequence_configs``), then its points refined from its lines (``lines.refine_points_px``
    above 0, ``_refined_configs``)."""
    configs, geometries, fallbacks = {sequence: config for sequence in sequences}, [], []
    if auto_geometry is not None:
        configs, geometries, fallbacks = _sequence_configs(work, sequences, config, calibration,
                                                           auto_geometry, client, on_geometry)
    refinements = []
    if config.lines.refine_points_px > 0:
        refinements = _refined_configs(work, sequences, configs, calibration, client)
    if on_points is not None:
        for refinement in refinements:
            on_points(refinement)
    return configs, geometries, fallbacks, refinements


def _refined_configs(work: Sequence[FrameWork], sequences: Sequence[str], configs: dict[str, PipelineConfig],
                     calibration: Calibration | None, client) -> list[PointsRefinement]:
    """Return what ``refine.sequence_refinement`` makes of each of ``sequences`` (its frames in
    ``work``, its config in ``configs``) and move the points of ``configs`` by it; here or on the
    Dask ``client``'s workers, one task per sequence."""
    args = [([w.image for w in work if w.sequence == s], configs[s], s) for s in sequences]
    if client is None:
        found = [sequence_refinement(images, config, calibration, s) for images, config, s in args]
    else:
        found = cluster.map_ordered(client, _refinement_task, args, calibration=calibration)
    for refinement in found:
        if refinement.moved:
            configs[refinement.sequence] = shifted_points(configs[refinement.sequence], refinement.shift_px)
    return found


def _refinement_task(args: tuple, calibration: Calibration | None) -> PointsRefinement:
    """``sequence_refinement`` of one (images, config, sequence), as one Dask task."""
    images, config, sequence = args
    return sequence_refinement(images, config, calibration, sequence)


def _predict_frames(todo: Sequence[FrameWork], configs: dict[str, PipelineConfig],
                    calibration: Calibration | None, client, desc: str, progress: bool) -> list[FrameOutcome]:
    """Return the outcome of each frame of ``todo`` after predicting it here (``predict_frame``,
    one pipeline cache) or, with a Dask ``client``, in chunks on its workers (``predict_chunk``)."""
    outcomes, cache = [], {}
    with tqdm(total=len(todo), desc=desc, unit="frame", disable=not progress, dynamic_ncols=True) as bar:
        if client is None:
            for w in todo:
                outcomes.append(predict_frame(w, configs[w.sequence], calibration, cache))
                bar.update(1)
        else:
            chunks = cluster.split(todo, cluster.chunk_size(len(todo), cluster.total_threads(client)))
            done = cluster.map_chunks(client, predict_chunk, chunks, bar, calibration=calibration,
                                      configs=configs)
            outcomes = _check_visible([o for chunk in done for o in chunk], todo)
    return outcomes


def predict_benchmark(benchmark: str, root: str | os.PathLike, out_dir: str | os.PathLike,
                      list_file: str | os.PathLike | None = None,
                      config: PipelineConfig | None = None, calibration: Calibration | None = None,
                      calibration_file: str | os.PathLike | None = None,
                      auto_geometry: GeometryOptions | None = None, progress: bool = True,
                      on_geometry: Callable[[str, RoadGeometry | GeometryFallback], None] | None = None,
                      on_points: Callable[[PointsRefinement], None] | None = None,
                      workers: int = 1, scheduler: str | None = None) -> PredictRun:
    """Return what the run did after predicting every labelled frame of a benchmark dataset.

    Each frame is detected on its own (``predict_frame``: the labelled frames are seconds apart,
    so no tracking) and written in the benchmark's format under ``out_dir``: TuSimple as one part
    per frame in ``out_dir/parts/`` assembled at the end into ``out_dir/predictions.json`` (the
    listed frames with a part, in list order); CULane as one ``.lines.txt`` per image mirroring
    the list (``evaluate culane --pred out_dir``).

    Resuming: a frame whose prediction file exists is skipped, so a run that was stopped goes on
    where it was. Every file is written atomically (temporary file, then rename): a stop leaves
    whole per-frame files and never a half-written one, and the TuSimple file is only written
    once the frames are done (a killed process's temporaries are removed when their file is next
    written). ``out_dir/predict.json`` records the settings; a run with other settings (config,
    calibration, geometry options, dataset) refuses to add to that folder.

    Parameters
    ----------
    benchmark, root, list_file : the dataset (``benchmark_work``).
    config : as for ``LanePipeline``; None (the default): ``benchmark_config``, the
        bundled preset of the benchmark's camera. Frames of another size than its
        ``perspective.size_px`` get its points scaled to their size (``LanePipeline``), which is
        right for resized copies of the same camera's frames; the thresholds' widths in px are
        not scaled (in a smaller frame they span more road).
    calibration : as for ``LanePipeline``; ``calibration_file`` names it in the settings record.
    auto_geometry : estimate the bird's-eye points and scale once per sequence (one camera's
        folder, ``frame_sequence``) from up to ``max_frames`` of its frames, and use them for that
        sequence's frames instead of ``config.perspective`` (only sequences with frames still to
        predict are estimated). Where the estimate fails or its confidence is too low
        (``_sequence_geometry``), the sequence keeps ``config.perspective`` and the run goes on:
        ``PredictRun.fallbacks`` says which and why.
    progress : show a tqdm bar.
    on_geometry : called with (sequence, geometry or ``GeometryFallback``) for each estimate, in
        list order, before any frame is predicted (the CLI prints them).
    on_points : called with each sequence's ``PointsRefinement`` (``config.lines.refine_points_px``
        above 0: the points moved to where the lines of the sequence's frames meet, after its
        geometry estimate if any), in list order, before any frame is predicted.
    workers, scheduler : where the frames are predicted (``cluster.dask_client``): 1 worker (the
        default) in this process; more on a Dask ``LocalCluster`` of that many processes; or the
        workers of the Dask scheduler at ``scheduler``. With Dask the frames go in chunks
        (``cluster.chunk_size``) to the workers, which read the images and write the predictions
        themselves (``predict_chunk``: with ``scheduler`` the dataset and ``out_dir`` must be on a
        filesystem the workers share, at the same path); the geometries too are estimated on the
        workers, one task per sequence, all before any frame; the outputs are the same as in one
        process (``run_time`` aside).

    Raises
    ------
    InputError
        For a bad dataset or list (``benchmark_work``) or a folder of other settings; nothing is
        written then.
    """
    out = Path(out_dir)
    config = benchmark_config(benchmark) if config is None else config
    work = benchmark_work(benchmark, root, out, list_file)
    settings = _settings(benchmark, Path(root), config,
                         None if calibration_file is None else str(calibration_file), auto_geometry)
    recorded = _check_settings(out, settings)
    t0 = time.perf_counter()
    todo = [w for w in work if not w.target.is_file()]
    # the cluster is reached before anything is written: a bad --scheduler leaves no trace
    with (cluster.dask_client(workers, scheduler) if todo else cluster.dask_client()) as client:
        sequences = list(dict.fromkeys(w.sequence for w in todo))
        configs, geometries, fallbacks, refinements = _sequence_setup(
            work, sequences, config, calibration, auto_geometry, client, on_geometry, on_points)
        if not recorded:
            _record_settings(out, settings)
        outcomes = _predict_frames(todo, configs, calibration, client, f"predict {benchmark}", progress)
    output = out
    if benchmark == "tusimple":
        output = _assemble_tusimple(work, out, tusimple.label_files(list_file or root, tasks=True))
    return PredictRun(len(work), len(work) - len(todo), tuple(outcomes), output,
                      time.perf_counter() - t0, tuple(geometries), tuple(fallbacks), tuple(refinements))
