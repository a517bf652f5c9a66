"""The CULane benchmark's files: the image list, ``.lines.txt`` labels and predictions, and scoring.

A list file (``list/test.txt``) names one image per line relative to the dataset root
(``/driver_37_30frame/05181432_0203.MP4/00000.jpg``; ``train_gt.txt`` adds more columns, of which
the first is the image). Beside each image, ``00000.lines.txt`` holds its lanes, one per line as
``x y x y ...`` (px). Predictions use the same layout under their own folder: the official tool
(``evaluate.cpp``) reads ``PRED_DIR + <image path without its suffix> + .lines.txt``, and a
missing prediction file counts as an image with no lanes. The metric is in ``metrics.py``.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Iterable, Mapping, Sequence

import numpy as np

from .. import cluster
from ..errors import InputError
from ..io import write_text
from .metrics import (CULANE_IMAGE_SIZE, CULANE_IOU, CULANE_LANE_WIDTH_PX, CULaneCounts,
                      culane_image)

LINES_SUFFIX = ".lines.txt"
# rows (px) at which lanelib gives a lane's points, bottom up, every 10 px as CULane's labels do
# (theirs start at y = 590, one below the image; these at the last row that is a multiple of 10)
SAMPLE_ROWS_PX = tuple(range(CULANE_IMAGE_SIZE[1] - 10, 0, -10))
LINES_PER_SIDE = 2  # CULane labels at most two lines on each side of the car (predict keeps as many)


def default_list(root: str | os.PathLike) -> Path:
    """Return the list of a CULane root's frames when none is named: its ``list/test.txt`` (the
    official test list), else a ``list.txt`` at the root (as the dev set has); ``list/test.txt``
    when it holds neither (``read_list`` then says it is missing)."""
    r = Path(root)
    official, flat = r / "list" / "test.txt", r / "list.txt"
    return flat if not official.is_file() and flat.is_file() else official


def read_list(path: str | os.PathLike) -> list[str]:
    """Return the image entries of a CULane list file (the first column, blank lines skipped)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such CULane list file; pass e.g. list/test.txt of the dataset")
    try:
        text = p.read_text(encoding="utf-8")
    except (UnicodeDecodeError, OSError) as e:
        raise InputError(f"{p}: cannot be read as text ({e}); pass a CULane list file") from None
    entries = []
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        entry = line.split()[0]
        if not PurePosixPath(entry).suffix or entry.endswith("/") or ".." in PurePosixPath(entry).parts:
            raise InputError(f"{p}:{n}: {entry!r} is not an image path inside the dataset; each line "
                             "names one image, e.g. /driver_37_30frame/05181432_0203.MP4/00000.jpg")
        entries.append(entry)
    if not entries:
        raise InputError(f"{p}: names no images; pass a list file with one image path per line")
    return entries


def lines_path(root: str | os.PathLike, entry: str) -> Path:
    """Return where the lanes of list ``entry`` live under ``root``: the image's ``NAME.lines.txt``."""
    rel = PurePosixPath(entry.lstrip("/"))
    return Path(root).joinpath(*rel.parent.parts, rel.stem + LINES_SUFFIX)


def parse_lines(text: str, where: str) -> list[np.ndarray]:
    """Return the lanes of a ``.lines.txt`` text, each an (n, 2) float array of x, y (px).

    Blank lines are skipped; a line with a word that is not a finite number, or with an odd
    count of numbers, raises ``InputError`` naming ``where`` and the line.
    """
    lanes = []
    for n, line in enumerate(text.splitlines(), 1):
        words = line.split()
        if not words:
            continue
        try:
            values = [float(w) for w in words]
        except ValueError:
            raise InputError(f"{where}:{n}: not a list of numbers; each line is one lane as "
                             "x y x y ... in pixels") from None
        if len(values) % 2 or not all(math.isfinite(v) for v in values):
            raise InputError(f"{where}:{n}: {len(values)} numbers; each line is one lane as pairs "
                             "x y (an even count of finite numbers)")
        lanes.append(np.asarray(values, np.float64).reshape(-1, 2))
    return lanes


def read_lines(path: str | os.PathLike) -> list[np.ndarray]:
    """Return the lanes of one ``.lines.txt`` file (see ``parse_lines``)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{p}: no such lanes file; check the path") from None
    except (UnicodeDecodeError, OSError) as e:
        raise InputError(f"{p}: cannot be read as text ({e}); regenerate the lanes file") from None
    return parse_lines(text, str(p))


def format_lines(lanes: Iterable[np.ndarray]) -> str:
    """Return lanes as the text of a ``.lines.txt`` file: one lane per line, ``x y x y ...``."""
    out = []
    for lane in lanes:
        pts = np.asarray(lane, np.float64).reshape(-1, 2)
        out.append(" ".join(f"{v:.10g}" for v in pts.ravel()) + "\n")
    return "".join(out)


def _write_lanes(root: str | os.PathLike, lanes: Mapping[str, Sequence[np.ndarray]],
                 inputs: Iterable[str | os.PathLike]) -> list[Path]:
    """Write each entry's lanes to ``lines_path(root, entry)`` atomically; return the files."""
    inputs = list(inputs)
    return [write_text(lines_path(root, entry), format_lines(entry_lanes), inputs=inputs)
            for entry, entry_lanes in lanes.items()]


def write_predictions(out_dir: str | os.PathLike, predictions: Mapping[str, Sequence[np.ndarray]],
                      inputs: Iterable[str | os.PathLike] = ()) -> list[Path]:
    """Write each entry's predicted lanes to ``out_dir`` mirroring the list layout, atomically.

    Parameters
    ----------
    out_dir : the prediction folder (``PRED_DIR`` of ``evaluate``).
    predictions : list entry (``/driver_xx/xx.MP4/00000.jpg``) -> its lanes, each (n, 2) x, y px.
    inputs : files never to write over (the labels).
    """
    return _write_lanes(out_dir, predictions, inputs)


def write_labels(root: str | os.PathLike, labels: Mapping[str, Sequence[np.ndarray]],
                 inputs: Iterable[str | os.PathLike] = ()) -> list[Path]:
    """Write each entry's labelled lanes beside its image under the dataset ``root``, atomically."""
    return _write_lanes(root, labels, inputs)


def write_list(path: str | os.PathLike, entries: Iterable[str]) -> Path:
    """Write a list file (``list/test.txt``): one image entry per line, atomically."""
    return write_text(path, "".join(f"{e}\n" for e in entries))


@dataclass(frozen=True)
class CULaneSet:
    """The entries of a list file with their labelled lanes (``read_labels``)."""

    entries: tuple[str, ...]
    lanes: tuple[tuple[np.ndarray, ...], ...]


def read_labels(root: str | os.PathLike, list_file: str | os.PathLike) -> CULaneSet:
    """Return the labelled lanes of every image of a list file under the dataset ``root``.

    A list entry without its ``.lines.txt`` raises ``InputError`` naming the entry, its line in
    the list and the file looked for.
    """
    r = Path(root)
    if not r.is_dir():
        raise InputError(f"{r}: no such folder; pass the CULane dataset root (the folder that holds "
                         "driver_*/ and list/)")
    entries = read_list(list_file)
    lanes = []
    for n, entry in enumerate(entries, 1):
        f = lines_path(r, entry)
        if not f.is_file():
            raise InputError(f"{list_file}: entry {n} ({entry}) has no labels: {f} is missing; pass the "
                             "dataset root the list is relative to, or a list of labelled images")
        lanes.append(tuple(read_lines(f)))
    return CULaneSet(tuple(entries), tuple(lanes))


def read_predictions(pred_dir: str | os.PathLike, entries: Sequence[str]) -> tuple[list[list[np.ndarray]], int]:
    """Return the predicted lanes of each entry and how many entries had no prediction file.

    A missing file counts as an image with no lanes, as in the official tool; a folder with none
    of the files raises ``InputError`` (the wrong folder, most likely).
    """
    d = Path(pred_dir)
    if not d.is_dir():
        raise InputError(f"{d}: no such prediction folder; pass the folder the .lines.txt "
                         "predictions were written to")
    out, missing = [], 0
    for entry in entries:
        f = lines_path(d, entry)
        if f.is_file():
            out.append(read_lines(f))
        else:
            out.append([])
            missing += 1
    if entries and missing == len(entries):
        raise InputError(f"{d}: holds no prediction for any listed image (looked for e.g. "
                         f"{lines_path(d, entries[0])}); pass the folder that mirrors the list's paths")
    return out, missing


@dataclass(frozen=True)
class CULaneScore:
    """The official CULane figures of a prediction folder, and how many images had no prediction."""

    counts: CULaneCounts
    missing_predictions: int = 0

    def to_dict(self) -> dict:
        """Return the figures as JSON-able values (``CULaneCounts.to_dict`` and the missing count)."""
        return {**self.counts.to_dict(), "missing_predictions": self.missing_predictions}

    def table(self) -> str:
        """Return the figures as printable lines."""
        text = self.counts.table()
        if self.missing_predictions:
            text += (f"\n{self.missing_predictions} images had no prediction file "
                     "(scored as no lanes)")
        return text


def score_chunk(pairs: Sequence[tuple[Sequence[np.ndarray], Sequence[np.ndarray]]],
                image_size: tuple[int, int] = CULANE_IMAGE_SIZE, width_px: int = CULANE_LANE_WIDTH_PX,
                iou_threshold: float = CULANE_IOU) -> list[CULaneCounts]:
    """Return ``metrics.culane_image`` of each (labels, predictions) pair of a chunk of images."""
    return [culane_image(gt, pred, image_size, width_px, iou_threshold) for gt, pred in pairs]


def score(labels: CULaneSet, predictions: Sequence[Sequence[np.ndarray]],
          image_size: tuple[int, int] = CULANE_IMAGE_SIZE, width_px: int = CULANE_LANE_WIDTH_PX,
          iou_threshold: float = CULANE_IOU, workers: int = 1, scheduler: str | None = None,
          progress: bool = False) -> CULaneCounts:
    """Return TP, FP and FN summed over the images of ``labels`` (``metrics.culane_image``).

    ``workers``/``scheduler``: score the images in chunks on Dask (``cluster.dask_client``; the
    labels and predictions are sent to the workers, so they need no shared filesystem); the
    counts are those of one process. ``progress`` shows a tqdm bar.
    """
    counts = cluster.run_items(score_chunk, list(zip(labels.lanes, predictions)), workers, scheduler,
                               "evaluate culane", "image", progress, image_size=image_size,
                               width_px=width_px, iou_threshold=iou_threshold)
    return sum(counts, CULaneCounts())


def evaluate(root: str | os.PathLike, list_file: str | os.PathLike, pred_dir: str | os.PathLike,
             image_size: tuple[int, int] = CULANE_IMAGE_SIZE, width_px: int = CULANE_LANE_WIDTH_PX,
             iou_threshold: float = CULANE_IOU, workers: int = 1, scheduler: str | None = None,
             progress: bool = False) -> CULaneScore:
    """Return the official CULane figures of the predictions in ``pred_dir`` for a list file.

    Parameters
    ----------
    root : the dataset root the list's paths are relative to (labels beside the images).
    list_file : the list of images to score (``list/test.txt``).
    pred_dir : the folder of ``.lines.txt`` predictions mirroring the list's paths.
    image_size : (width, height) px of the drawing canvas (CULane: 1640 x 590).
    width_px : thickness of the drawn lanes (CULane: 30).
    iou_threshold : IoU above which a matched pair is a true positive (CULane: 0.5).
    workers, scheduler, progress : as for ``score`` (the files are read here, the IoUs computed
        on the workers).
    """
    if width_px < 1:
        raise InputError(f"lane width {width_px} px: give 1 px or more (CULane: 30)")
    if not 0.0 <= iou_threshold < 1.0:
        raise InputError(f"IoU threshold {iou_threshold}: give a value from 0 to below 1 (CULane: 0.5)")
    labels = read_labels(root, list_file)
    preds, missing = read_predictions(pred_dir, labels.entries)
    return CULaneScore(score(labels, preds, image_size, width_px, iou_threshold, workers, scheduler,
                             progress), missing)
