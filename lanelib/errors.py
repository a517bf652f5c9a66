"""Errors raised by lanelib. Every error says what was wrong, with which file, and what to do."""


class LaneLibError(Exception):
    """Base class of every error lanelib raises on purpose."""


class InputError(LaneLibError):
    """A file or array given to lanelib is missing, unreadable or of the wrong kind."""


class CalibrationError(LaneLibError):
    """Camera calibration failed or does not fit the frames it is used on."""


class ConfigError(LaneLibError):
    """A configuration value or file is invalid (unknown key, wrong type, out of range)."""
