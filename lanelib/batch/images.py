"""A folder of images, run image by image: ``run_images`` and the rows of ``results.json``.

``run_images`` takes a ``process`` callable that turns one RGB image into an output image and a
row of numbers, and does the reading, writing and results file, all written atomically and never
over an input. On Dask (``cluster.dask_client``) the files go in chunks (``image_chunk``), each
processed by the ``process`` a picklable factory builds on the worker, with the rows of one
process. A file that cannot be read or processed (a lanelib error) gets its own row with an
``error`` and the run goes on.
"""
from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
from tqdm import tqdm

from .. import cluster, io
from ..errors import ConfigError, LaneLibError, naming_the_file

# process(rgb) -> (output rgb, row of JSON-able values)
ImageFn = Callable[[np.ndarray], tuple[np.ndarray, dict]]


def json_value(value):
    """Return ``value`` as a JSON-safe scalar: numpy types unwrapped, NaN and inf as None."""
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


GRAYSCALE_NOTE = ("grayscale image: the colour masks (yellow) find nothing; gradient and "
                  "lightness masks still work")


def image_notes(info: io.ImageFileInfo) -> list[str]:
    """Return what a results row should say about how an image file was read (may be empty).

    A grey image (``GRAYSCALE_NOTE``), 16-bit samples scaled to 8 bits, and what the decoder
    printed about an image it could still decode (e.g. corrupt JPEG data).
    """
    notes = [GRAYSCALE_NOTE] if not info.colour else []
    if info.bit_depth == 16:
        notes.append("16-bit image: scaled to 8 bits (value >> 8)")
    notes += [f"the decoder warned: {m}" for m in info.decoder_messages]
    return notes


def _image_row(f: Path, out: Path, process: ImageFn, files: Sequence[Path]) -> dict:
    """Return the results row of one image after processing it and writing its output image."""
    try:
        rgb, info = io.read_image_info(f)
        image, row = process(rgb)
        io.write_image(out / f.name, image, inputs=files)
    except ConfigError:
        raise
    except LaneLibError as e:
        return {"file": f.name, "error": naming_the_file(str(e), f)}
    notes = image_notes(info)
    return {"file": f.name, **{k: json_value(v) for k, v in row.items()},
            **({"note": "; ".join(notes)} if notes else {})}


def image_chunk(chunk: Sequence[Path], out_dir: Path, make: Callable[[], ImageFn],
                files: Sequence[Path]) -> list[dict]:
    """Return the results rows of a chunk of images (a Dask task of ``run_images``): ``make()``
    gives the chunk's ``process`` (its pipelines built once per chunk)."""
    process = make()
    return [_image_row(f, out_dir, process, files) for f in chunk]


def run_images(files: Sequence[str | os.PathLike], out_dir: str | os.PathLike, process: ImageFn | None,
               results_name: str = "results.json", make: Callable[[], ImageFn] | None = None,
               client=None, progress: bool = True) -> list[dict]:
    """Process each image, write ``OUT_DIR/<name>`` and ``OUT_DIR/results.json``; return the rows.

    Each row is ``{"file": <input file name>, **row}``, with ``"note"`` when the image was grey,
    16-bit or slightly corrupt (``image_notes``). A file that fails with a lanelib error (unreadable,
    not an image, a size the calibration does not fit, ...) gets the row ``{"file": <name>,
    "error": <one line naming the file, the cause and the fix>}``, no output image, and the run
    goes on. Any other exception is a bug and stops the run, as does a ``ConfigError`` (a bad
    configuration fails every file alike).

    With a Dask ``client`` (``cluster.dask_client``) the files go in chunks to its workers
    (``cluster.map_items``, one progress bar unless ``progress`` is false), each chunk processed
    by the ``process`` that ``make()`` (a picklable factory, e.g. a ``functools.partial`` of a
    module-level function) builds there; the workers write the images, this process the results
    file, with the rows of one process.

    Raises
    ------
    InputError
        If the output folder is the input folder.
    """
    out = Path(out_dir)
    files = [Path(f) for f in files]
    if any(f.parent.resolve() == out.resolve() for f in files):
        raise io.InputError(f"{out}: the output folder is the input folder; choose another -o folder")
    if client is None:
        process = process if process is not None else make()
        rows = [_image_row(f, out, process, files) for f in files]
    else:
        with tqdm(total=len(files), desc=out.name, unit="image", disable=not progress,
                  dynamic_ncols=True) as bar:
            rows = cluster.map_items(client, image_chunk, files, bar, out_dir=out, make=make, files=files)
    io.write_json(out / results_name, rows, inputs=files)
    return rows
