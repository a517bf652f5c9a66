"""Errors raised by lanelib. Every error says what was wrong, with which file, and what to do."""
from __future__ import annotations

import os


class LaneLibError(Exception):
    """Base class of every error lanelib raises on purpose."""


class InputError(LaneLibError):
    """A file or array given to lanelib is missing, unreadable or of the wrong kind."""


class CalibrationError(LaneLibError):
    """Camera calibration failed or does not fit the frames it is used on."""


class ConfigError(LaneLibError):
    """A configuration value or file is invalid (unknown key, wrong type, out of range)."""


class GeometryError(LaneLibError):
    """The road geometry could not be estimated from the frames (``geometry``): no road, too few
    segments, no common vanishing point, a road not straight, or vanishing points that disagree
    from frame to frame. The message names the reason and the fix.
    """


class DecodeStoppedError(InputError):
    """A video stopped decoding part-way (truncated or corrupt) after ``frames`` frames, which
    ``VideoReader`` yielded; a run may keep what it made of them (``batch.run_video`` does, and
    raises ``PartialOutputError``).
    """

    def __init__(self, message: str, frames: int, cause: str):
        super().__init__(message)
        self.frames = frames
        self.cause = cause


class PartialOutputError(LaneLibError):
    """A run stopped early on a broken input: the outputs named in the message were written
    (atomically) and hold the ``frames`` frames processed before; the CLI exits with code 1.
    """

    def __init__(self, message: str, frames: int):
        super().__init__(message)
        self.frames = frames


def naming_the_file(message: str, path: str | os.PathLike, *related: str | os.PathLike) -> str:
    """Return ``message`` led by ``path`` unless it already names that file or one of ``related``
    (files belonging to ``path``, e.g. the truth file beside an image).
    """
    named = any(os.path.basename(f) in message for f in (path, *related))
    return message if named else f"{path}: {message}"
