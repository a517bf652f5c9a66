"""The why-images: a frame drawn with what became of each line (``why.draw_why``'s picture of
``why.explain_frame``), and the images of frames named on the command line (``write_why``,
``python -m lanelib why culane|tusimple FRAME ...``).
"""
from __future__ import annotations

import os
from pathlib import Path, PurePosixPath
from typing import Callable, Sequence

import cv2
import numpy as np

from .. import batch, data, draw, io
from ..batch.refine import PointsRefinement
from ..config import PipelineConfig
from ..errors import InputError
from . import culane
from .why import FALSE, FOUND, REFUSED, FrameWhy, explain_frame, refined_configs, set_frames, written_points

COLOURS = {"label": (0, 220, 0), FOUND: (255, 40, 40), FALSE: (255, 150, 0), REFUSED: (170, 170, 170)}


# --------------------------------------------------------------------------- drawing

def _polyline(out: np.ndarray, pts: np.ndarray, colour, thickness: int) -> None:
    if len(pts) >= 2:
        cv2.polylines(out, [np.round(pts).astype(np.int32).reshape(-1, 1, 2)], False, colour, thickness,
                      cv2.LINE_AA)


def _text(out: np.ndarray, text: str, at: tuple[int, int], colour, scale: float) -> None:
    """Write ``text`` at ``at`` (its baseline's left end) on a black box, in place."""
    thick = max(1, int(round(2 * scale)))
    (w, h), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
    x, y = at
    cv2.rectangle(out, (x - 2, y - h - 2), (x + w + 2, y + base), (0, 0, 0), -1)
    cv2.putText(out, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, scale, colour, thick, cv2.LINE_AA)


def _inset(out: np.ndarray, why: FrameWhy) -> None:
    """Draw the lines view's mask, the labels mapped into it in green, at the top right of ``out``."""
    view = draw.mask_to_rgb(why.mask) // 2
    for pts in why.view_labels:
        _polyline(view, pts, COLOURS["label"], max(2, view.shape[1] // 200))
    w = out.shape[1] // 5
    h = max(1, int(round(view.shape[0] * w / view.shape[1])))
    h = min(h, out.shape[0])
    small = draw.shrink(view, (w, h))
    out[:h, -w:] = small
    cv2.rectangle(out, (out.shape[1] - w, 0), (out.shape[1] - 1, h - 1), (255, 255, 255), 1)


def draw_why(image, why: FrameWhy, inset: bool = True) -> np.ndarray:
    """Return the frame with its labels (green), predicted lines (red: matched, orange: false),
    refused lines (thin grey, with the first words of the reason), each label's class at its
    near end, the classes as text at the top left, and the lines view's mask as an inset.

    Parameters
    ----------
    image : the frame (a path or an RGB array), resized to ``why.size`` when it is not.
    why : the frame's ``explain_frame``.
    inset : draw the mask inset at the top right (when ``why`` kept it).

    Examples
    --------
    >>> rows = np.arange(580.0, 200.0, -10.0)
    >>> road = np.full((590, 1640, 3), 70, np.uint8)
    >>> why = explain_frame("culane", road, [np.column_stack([600 + 0.6 * (rows - 580), rows])])
    >>> draw_why(road, why).shape
    (590, 1640, 3)
    """
    rgb = image if isinstance(image, np.ndarray) else io.read_image(image)
    if (rgb.shape[1], rgb.shape[0]) != why.size:
        rgb = cv2.resize(rgb, why.size, interpolation=cv2.INTER_CUBIC)
    out = rgb.copy()
    scale = why.size[0] / 1640
    for xs, reason in why.refused:
        pts = written_points(xs, why.rows_px)
        _polyline(out, pts, COLOURS[REFUSED], max(1, int(2 * scale)))
        if len(pts):
            top = pts[np.argmin(pts[:, 1])]
            _text(out, reason.split(",")[0][:40], (int(top[0]), int(top[1]) - 4), COLOURS[REFUSED], 0.45 * scale)
    for pts in why.labels:
        _polyline(out, pts, COLOURS["label"], max(2, int(10 * scale)))
    matched = {w.prediction for w in why.of(FOUND)}
    for j, xs in enumerate(why.predictions):
        _polyline(out, written_points(xs, why.rows_px), COLOURS[FOUND if j in matched else FALSE], max(2, int(4 * scale)))
    for w in why.lines:
        if w.label is not None and len(why.labels[w.label]):
            near = why.labels[w.label][np.argmax(why.labels[w.label][:, 1])]
            at = (int(np.clip(near[0], 0, why.size[0] - 150 * scale)), int(min(near[1], why.size[1] - 10)) - 6)
            _text(out, f"{w.label + 1} {w.category}", at, (255, 255, 255), 0.7 * scale)
    for k, text in enumerate(why.summary()[:8]):
        _text(out, text[:110], (10, int((24 + 22 * k) * scale)), (255, 255, 255), 0.55 * scale)
    if inset and why.mask is not None:
        _inset(out, why)
    return out


# --------------------------------------------------------------------------- frames named by the user

def frame_labels(benchmark: str, image: Path, root: Path | None) -> tuple[str, object]:
    """Return the name and labels of one frame: CULane's ``.lines.txt`` beside the image;
    TuSimple's record of the image (its path under ``root``) in ``root``'s labels."""
    if benchmark == "culane":
        return str(image), culane.read_lines(image.with_name(image.stem + culane.LINES_SUFFIX))
    if root is None:
        raise InputError(f"{image}: a TuSimple frame's labels are in its dataset's label file; "
                         "pass the dataset root")
    try:
        name = image.resolve().relative_to(root.resolve()).as_posix()
    except ValueError:
        raise InputError(f"{image}: not under the dataset root {root}; pass a frame of that "
                         "dataset or its root") from None
    for rec_name, _, rec in set_frames(benchmark, root):
        if rec_name.lstrip("/") == name:
            return name, rec
    raise InputError(f"{image}: not labelled in {root}'s label file; pass a labelled frame")


def why_png(out_dir: Path, name: str) -> Path:
    """Return where the why-image of frame ``name`` goes: its path's parts joined by "_", .png.

    Examples
    --------
    >>> why_png(Path("out"), "/driver_161_90frame/06030819_0755.MP4/00000.jpg").as_posix()
    'out/driver_161_90frame_06030819_0755.MP4_00000.png'
    """
    parts = PurePosixPath(name.replace(os.sep, "/").lstrip("/")).with_suffix("").parts
    return out_dir / ("_".join(p for p in parts if p not in ("", "..", ".")) + ".png")


def write_why(benchmark: str, frames: Sequence[str | os.PathLike], out_dir: str | os.PathLike,
              root: str | os.PathLike | None = None, config: PipelineConfig | None = None,
              on_points: Callable[[PointsRefinement], None] | None = None) -> list[tuple[FrameWhy, Path]]:
    """Explain each frame (a path, or a name under ``root``) and write its ``draw_why`` image to
    ``out_dir`` (``why_png``), atomically; return each frame's record and image file.

    ``root`` defaults to the dev set (``data.culane_dev``, ``data.tusimple_dev``) when present.
    Each frame's sequence is seen through the points ``predict`` gives it (``why.refined_configs``,
    each ``PointsRefinement`` to ``on_points``), refined from the sequence's frames in the
    dataset's list (``set_frames``), else from the frames named.
    Nothing is written when a frame is missing, or ``out_dir`` is a folder a frame lies in or
    the dataset root (``InputError``): every check runs before the first frame.
    """
    out = Path(out_dir)
    base = Path(root) if root is not None else (data.culane_dev() if benchmark == "culane"
                                                else data.tusimple_dev())
    images = [_frame_path(f, base) for f in frames]
    for p in images:
        for folder, what in ((p.parent, f"the folder of the frame {p}"), (base, "the dataset root")):
            if folder is not None and out.resolve() == folder.resolve():
                raise InputError(f"{out}: is {what}; choose another output folder (-o), the images "
                                 "are never written among the inputs")
    config = batch.benchmark_config(benchmark) if config is None else config
    named = [(frame_labels(benchmark, p, base), p) for p in images]
    in_set = [name if benchmark == "tusimple" else _relative(p, base).as_posix() for (name, _), p in named]
    configs = refined_configs(benchmark, _sequence_images(benchmark, list(zip(in_set, images)), base),
                              config, on_points)
    done = []
    for ((name, labels), p), rel in zip(named, in_set):
        own = configs.get(batch.frame_sequence(benchmark, rel), config)
        frame = explain_frame(benchmark, p, labels, own, name=name)
        target = why_png(out, rel)
        done.append((frame, io.write_image(target, draw_why(p, frame), inputs=images)))
    return done


def _sequence_images(benchmark: str, named: list[tuple[str, Path]], base: Path | None) -> list[tuple[str, Path]]:
    """Return the (name, path) frames that the sequences of ``named`` are refined from, as
    ``predict`` on the dataset refines them: each sequence's frames in the dataset's list
    (``set_frames`` of ``base``), else the frames named."""
    wanted = {batch.frame_sequence(benchmark, n) for n, _ in named}
    try:
        listed = [(n, i) for n, i, _ in set_frames(benchmark, base)] if base is not None else []
    except InputError:  # a folder of frames without the dataset's list
        listed = []
    listed = [(n, i) for n, i in listed if batch.frame_sequence(benchmark, n) in wanted]
    have = {batch.frame_sequence(benchmark, n) for n, _ in listed}
    return listed + [(n, p) for n, p in named if batch.frame_sequence(benchmark, n) not in have]


def _frame_path(frame: str | os.PathLike, base: Path | None) -> Path:
    """Return a frame named by a path, or by its name under the dataset root ``base``."""
    p = Path(frame)
    if not p.is_file() and base is not None and (base / str(frame).lstrip("/")).is_file():
        p = base / str(frame).lstrip("/")
    if not p.is_file():
        under = f" and under {base}" if base is not None else ""
        raise InputError(f"{frame}: no such frame (looked for it as a path{under}); check the name")
    return p


def _relative(path: Path, base: Path | None) -> Path:
    if base is not None:
        try:
            return path.resolve().relative_to(base.resolve())
        except ValueError:
            pass
    return Path(path.name)
