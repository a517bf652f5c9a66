"""The TuSimple lane benchmark's files: labels, predictions, and scoring a prediction file.

Labels (``label_data_0313.json``, ``label_data_0531.json``, ``label_data_0601.json``,
``test_label.json``) are JSON lines, one image each::

    {"lanes": [[-2, -2, 632, 625, ...], ...], "h_samples": [240, 250, ...], "raw_file": "clips/..."}

``lanes`` holds one list per lane with one x (px) per ``h_samples`` row, -2 where the lane has
no point. Predictions are JSON lines in the same layout with ``run_time`` (ms) added; the
official script (``evaluate/lane.py`` of TuSimple/tusimple-benchmark) reads ``raw_file``,
``lanes`` and ``run_time`` and takes the rows from the label. The metric is in ``metrics.py``.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

import cv2
import numpy as np

from .. import cluster
from ..errors import InputError
from ..io import write_text
from .metrics import TuSimpleImage, TuSimpleScore, tusimple_image, tusimple_score

NO_POINT = -2  # the x TuSimple writes where a lane has no point
H_SAMPLES_PX = tuple(range(160, 720, 10))  # the rows of most TuSimple labels (1280x720; some from 240)
IMAGE_SIZE = (1280, 720)  # (width, height) px of TuSimple's frames, the size its official rows are at
# TuSimple expects at most 4 lines around the centre of sight: the current lane's and the left
# and right lanes' (its readme; a third on one side where the other side has no lane), so
# predict keeps the 4 nearest the car
MAX_LINES = 4


def full_size(rgb: np.ndarray, interpolation: int = cv2.INTER_CUBIC) -> np.ndarray:
    """Return a TuSimple frame at ``IMAGE_SIZE``, where the official label rows lie: resized
    (``interpolation``, an OpenCV flag: bicubic by default) when it is stored smaller (a
    downscaled copy), else the frame itself.

    Examples
    --------
    >>> full_size(np.zeros((288, 512, 3), np.uint8)).shape
    (720, 1280, 3)
    """
    if (rgb.shape[1], rgb.shape[0]) == IMAGE_SIZE:
        return rgb
    return cv2.resize(rgb, IMAGE_SIZE, interpolation=interpolation)


@dataclass(frozen=True)
class TuSimpleRecord:
    """One image of a TuSimple label or prediction file.

    Parameters
    ----------
    raw_file : the image path as the label names it (``clips/0530/.../20.jpg``).
    lanes : one tuple per lane, one x (px) per ``h_samples`` row, ``NO_POINT`` (-2) for none.
    h_samples : the rows (px).
    run_time_ms : the prediction's time for this image (ms); None in a label.
    """

    raw_file: str
    lanes: tuple[tuple[float, ...], ...]
    h_samples: tuple[float, ...]
    run_time_ms: float | None = None

    def to_json(self) -> dict:
        """Return the record as TuSimple writes it (``run_time`` only when it has one)."""
        out = {"raw_file": self.raw_file, "lanes": [[_number(x) for x in lane] for lane in self.lanes],
               "h_samples": [_number(y) for y in self.h_samples]}
        if self.run_time_ms is not None:
            out["run_time"] = _number(self.run_time_ms)
        return out


def _number(v: float):
    """Return ``v`` as an int when it is whole (TuSimple's files hold whole pixels)."""
    return int(v) if float(v).is_integer() else float(v)


def _numbers(value, where: str, what: str) -> tuple[float, ...]:
    """Return a JSON list of finite numbers as floats; anything else raises InputError."""
    if not isinstance(value, list) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value):
        raise InputError(f"{where}: {what} must be a list of numbers; fix the line or regenerate the file")
    return tuple(float(v) for v in value)


def parse_record(line: str, where: str, prediction: bool, task: bool = False) -> TuSimpleRecord:
    """Return one JSON line of a label or prediction file as a ``TuSimpleRecord``.

    Parameters
    ----------
    line : the text of the line.
    where : ``FILE:LINE``, named in every error.
    prediction : True for a prediction line (``run_time`` is required, ``h_samples`` optional).
    task : a line of the test set's task file (``test_tasks_0627.json``): the frame to predict and
        its rows; ``lanes`` may be absent (no lanes).
    """
    try:
        obj = json.loads(line)
    except json.JSONDecodeError as e:
        raise InputError(f"{where}: not a JSON object ({e.msg}); each line of a TuSimple file is one "
                         "JSON object with raw_file, lanes and h_samples") from None
    need = (("raw_file", "lanes", "run_time") if prediction else
            ("raw_file", "h_samples") if task else ("raw_file", "lanes", "h_samples"))
    missing = [k for k in need if not isinstance(obj, dict) or k not in obj]
    if missing:
        raise InputError(f"{where}: no {', '.join(missing)}; each line needs {', '.join(need)}")
    if not isinstance(obj["raw_file"], str) or not obj["raw_file"]:
        raise InputError(f"{where}: raw_file must be the image path as text")
    if task:
        obj = {**obj, "lanes": obj.get("lanes", [])}
    if not isinstance(obj["lanes"], list):
        raise InputError(f"{where}: lanes must be a list of lanes, each a list of x values")
    lanes = tuple(_numbers(lane, where, f"lane {i + 1}") for i, lane in enumerate(obj["lanes"]))
    rows = _numbers(obj["h_samples"], where, "h_samples") if "h_samples" in obj else ()
    if not prediction and not rows:
        raise InputError(f"{where}: h_samples is empty; a label needs the rows its lanes are given at")
    for i, lane in enumerate(lanes):
        if rows and len(lane) != len(rows):
            raise InputError(f"{where}: lane {i + 1} has {len(lane)} x values for {len(rows)} "
                             "h_samples; give one x per row (-2 where the lane has no point)")
    run_time = None
    if prediction:
        t = obj["run_time"]
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t) or t < 0:
            raise InputError(f"{where}: run_time must be the time in ms (a number of 0 or more)")
        run_time = float(t)
    return TuSimpleRecord(obj["raw_file"], lanes, rows, run_time)


def _read(path: Path, prediction: bool, task: bool = False) -> list[TuSimpleRecord]:
    what = "TuSimple prediction file" if prediction else "TuSimple label file"
    if not path.is_file():
        raise InputError(f"{path}: no such {what}; check the path")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not text; pass the {what} (JSON lines)") from None
    except OSError as e:
        raise InputError(f"{path}: cannot be read ({e.strerror or e}); check its permissions") from None
    records = [parse_record(line, f"{path}:{n}", prediction, task)
               for n, line in enumerate(text.splitlines(), 1) if line.strip()]
    if not records:
        raise InputError(f"{path}: holds no lines; pass a {what} with one JSON object per image")
    seen: dict[str, int] = {}
    for n, r in enumerate(records, 1):
        if r.raw_file in seen:
            raise InputError(f"{path}: {r.raw_file} is given twice (records {seen[r.raw_file]} and "
                             f"{n}); keep one line per image")
        seen[r.raw_file] = n
    return records


def label_files(path: str | os.PathLike, tasks: bool = False) -> list[Path]:
    """Return the label files at ``path``: the file itself, or a folder's ``label_data*.json`` (the
    train set's), else its ``test_label*.json`` (the test set's labels), else, with ``tasks`` (the
    frames to predict), its ``test_tasks*.json`` (the test set's task file)."""
    p = Path(path)
    if not p.is_dir():
        return [p]
    kinds = ("label_data*.json", "test_label*.json") + (("test_tasks*.json",) if tasks else ())
    for kind in kinds:
        files = sorted(p.glob(kind))
        if files:
            return files
    raise InputError(f"{p}: holds no {' or '.join(kinds)}; pass a TuSimple label file or the folder "
                     "that holds one (the train set's root, or test_set/)")


def read_labels(path: str | os.PathLike, tasks: bool = False) -> list[TuSimpleRecord]:
    """Return the labelled images of a TuSimple label file, or of a folder's label files
    (``label_files``); with ``tasks``, also the frames of the test set's task file, whose lines
    may have no lanes.

    A malformed line, a lane whose length is not that of ``h_samples``, or an image given twice
    raises ``InputError`` naming the file and line.
    """
    records = []
    for f in label_files(path, tasks):
        records.extend(_read(f, prediction=False, task=tasks))
    seen = set()
    for r in records:
        if r.raw_file in seen:
            raise InputError(f"{path}: {r.raw_file} is labelled in two files; pass one of them")
        seen.add(r.raw_file)
    return records


def read_predictions(path: str | os.PathLike) -> list[TuSimpleRecord]:
    """Return the predicted images of a TuSimple prediction file (JSON lines with ``run_time``)."""
    return _read(Path(path), prediction=True)


def record_line(record: TuSimpleRecord, where: str | os.PathLike, prediction: bool) -> str:
    """Return one record as its JSON line (newline included), as a label or a prediction file holds it.

    A lane of another length than ``h_samples``, or a prediction without ``run_time_ms``, raises
    ``InputError`` naming ``where`` (the file it is meant for) and the image.
    """
    r = record
    if prediction and r.run_time_ms is None:
        raise InputError(f"{where}: the prediction of {r.raw_file} has no run_time; give each "
                         "image's time in ms")
    for i, lane in enumerate(r.lanes):
        if len(lane) != len(r.h_samples):
            raise InputError(f"{where}: lane {i + 1} of {r.raw_file} has {len(lane)} x values for "
                             f"{len(r.h_samples)} h_samples; give one x per row")
    obj = r.to_json()
    if not prediction:
        obj.pop("run_time", None)
    return json.dumps(obj, separators=(",", ":")) + "\n"


def write_predictions(path: str | os.PathLike, records: Iterable[TuSimpleRecord],
                      inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write predictions as TuSimple JSON lines, atomically (never over one of ``inputs``).

    Every record needs its ``run_time_ms``; a lane of another length than ``h_samples`` raises
    ``InputError`` (``record_line``).
    """
    return write_text(path, "".join(record_line(r, path, prediction=True) for r in records), inputs=inputs)


def write_labels(path: str | os.PathLike, records: Iterable[TuSimpleRecord],
                 inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write labels as TuSimple JSON lines (``label_data_*.json``: no ``run_time``), atomically."""
    return write_text(path, "".join(record_line(r, path, prediction=False) for r in records), inputs=inputs)


def score_chunk(pairs: Sequence[tuple[TuSimpleRecord, TuSimpleRecord]]) -> list[TuSimpleImage]:
    """Return ``metrics.tusimple_image`` of each (prediction, label) pair of a chunk of images."""
    return [tusimple_image(p.lanes, gt.lanes, gt.h_samples, p.run_time_ms or 0.0) for p, gt in pairs]


def score(labels: Sequence[TuSimpleRecord], predictions: Sequence[TuSimpleRecord],
          pred_name: str = "predictions", label_name: str = "labels", workers: int = 1,
          scheduler: str | None = None, progress: bool = False) -> TuSimpleScore:
    """Return the official TuSimple Accuracy, FP and FN of ``predictions`` against ``labels``.

    As TuSimple's ``bench_one_submit``: every labelled image needs one prediction and every
    prediction a label (else ``InputError`` naming the images); the rows are the label's (a
    prediction that gives other ``h_samples`` is an error here, where TuSimple ignores them).
    ``workers``/``scheduler``: score the images in chunks on Dask (``cluster.dask_client``; the
    records are sent to the workers); the figures are those of one process. ``progress`` shows
    a tqdm bar.
    """
    gts = {r.raw_file: r for r in labels}
    preds = {r.raw_file: r for r in predictions}
    unlabelled = [f for f in preds if f not in gts]
    if unlabelled:
        raise InputError(f"{pred_name}: {len(unlabelled)} predictions have no label in {label_name} "
                         f"(first: {unlabelled[0]}); predict the images of this label file")
    missing = [f for f in gts if f not in preds]
    if missing:
        raise InputError(f"{pred_name}: no prediction for {len(missing)} of the {len(gts)} labelled "
                         f"images (first: {missing[0]}); predict every image of {label_name}")
    pairs = []
    for raw_file, p in preds.items():
        gt = gts[raw_file]
        if p.h_samples and tuple(p.h_samples) != tuple(gt.h_samples):
            raise InputError(f"{pred_name}: {raw_file} is predicted at other h_samples than its label; "
                             "predict x at the label's rows")
        bad = [i + 1 for i, lane in enumerate(p.lanes) if len(lane) != len(gt.h_samples)]
        if bad:
            raise InputError(f"{pred_name}: {raw_file}: predicted lane {bad[0]} has "
                             f"{len(p.lanes[bad[0] - 1])} x values for {len(gt.h_samples)} h_samples; "
                             "give one x per label row")
        pairs.append((p, gt))
    images = cluster.run_items(score_chunk, pairs, workers, scheduler, "evaluate tusimple", "image", progress)
    return tusimple_score([(p.raw_file, image) for (p, _), image in zip(pairs, images)], len(gts))


def evaluate(labels: str | os.PathLike, predictions: str | os.PathLike, workers: int = 1,
             scheduler: str | None = None, progress: bool = False) -> TuSimpleScore:
    """Return the official TuSimple figures of a prediction file against a label file (or folder)
    (``workers``, ``scheduler``, ``progress``: as for ``score``)."""
    return score(read_labels(labels), read_predictions(predictions), str(predictions), str(labels),
                 workers, scheduler, progress)
