"""``PipelineConfig``: every tunable parameter of the pipelines, nested, saved and loaded as JSON.

Each stage's parameter record lives in ``params`` (``PerspectiveConfig``, ``ThresholdConfig``,
...); this module nests them, converts the nest to and from JSON and reads the bundled presets.
Loading is strict: an unknown key or a wrong type raises ``ConfigError`` naming the key's dotted
path (e.g. ``thresholds.white.low``). Keys a JSON file leaves out keep their defaults.
"""
from __future__ import annotations

import dataclasses
import json
import os
import types
import typing
from dataclasses import dataclass, fields, is_dataclass
from pathlib import Path

from . import io
from .errors import ConfigError
from .params import (DrawConfig, EdgeConfig, HoughConfig, LaneChecks, LinesConfig, PerspectiveConfig,
                     SearchConfig, ThresholdConfig, TrackerConfig)


@dataclass(frozen=True)
class PipelineConfig:
    """All parameters of the advanced pipeline (and of the basic Hough pipeline)."""

    perspective: PerspectiveConfig = PerspectiveConfig()
    thresholds: ThresholdConfig = ThresholdConfig()
    search: SearchConfig = SearchConfig()
    checks: LaneChecks = LaneChecks()
    tracking: TrackerConfig = TrackerConfig()
    draw: DrawConfig = DrawConfig()
    hough: HoughConfig = HoughConfig()
    lines: LinesConfig = LinesConfig()  # every visible line (``detect_lines``, ``predict``)
    edge: EdgeConfig = EdgeConfig()  # the asphalt edge of a side without paint (``roads.edge.road_edge``)


def to_dict(obj) -> dict:
    """Return a dataclass nest as plain dicts, lists and numbers (JSON-able)."""
    if is_dataclass(obj):
        return {f.name: to_dict(getattr(obj, f.name)) for f in fields(obj)}
    if isinstance(obj, (tuple, list)):
        return [to_dict(v) for v in obj]
    return obj


def _convert(value, tp, key: str):
    """Return ``value`` converted to type ``tp``; a mismatch raises ConfigError naming ``key``."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        options = typing.get_args(tp)
        if value is None and type(None) in options:
            return None
        errors = []
        for opt in options:
            if opt is type(None):
                continue
            try:
                return _convert(value, opt, key)
            except ConfigError as e:
                errors.append(str(e))
        raise ConfigError(errors[0] if errors else f"{key}: unexpected value {value!r}")
    if is_dataclass(tp):
        if not isinstance(value, dict):
            raise ConfigError(f"{key}: expected an object of {tp.__name__} fields, got {value!r}")
        return from_dict(tp, value, prefix=key)
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f"{key}: expected a list, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(v, args[0], f"{key}[{i}]") for i, v in enumerate(value))
        if len(value) != len(args):
            raise ConfigError(f"{key}: expected {len(args)} values, got {len(value)}")
        return tuple(_convert(v, a, f"{key}[{i}]") for i, (v, a) in enumerate(zip(value, args)))
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{key}: expected a number, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{key}: expected a whole number, got {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{key}: expected true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{key}: expected a string, got {value!r}")
        return value
    return value


# Keys of older files: (old section, key) -> the (section, key)s that take its value. The lane's
# checks are in ``checks`` (single images have them too); the old spread also bounded a bend.
MOVED_KEYS = {
    ("tracking", "min_width_m"): (("checks", "min_width_m"),),
    ("tracking", "max_width_m"): (("checks", "max_width_m"),),
    ("tracking", "max_width_spread_m"): (("checks", "max_width_spread_m"), ("tracking", "max_bend_m")),
    ("tracking", "max_curvature_diff_1pm"): (("checks", "max_curvature_diff_per_m"),),
    ("checks", "max_curvature_diff_1pm"): (("checks", "max_curvature_diff_per_m"),),
    ("tracking", "max_band_fill"): (("checks", "max_band_fill"),),
    ("tracking", "check_rows"): (("checks", "check_rows"),),
}


def migrate(data: dict) -> dict:
    """Return a PipelineConfig dict with the keys of older files moved to their place (``MOVED_KEYS``),
    unless the file sets the new key itself; setting both to different values raises
    ``ConfigError`` naming both.
    """
    moved = {k: dict(v) if isinstance(v, dict) else v for k, v in data.items()}
    explicit = {(sec, key) for sec, part in data.items() if isinstance(part, dict) for key in part}
    for (sec, key), targets in MOVED_KEYS.items():
        part = moved.get(sec)
        if not isinstance(part, dict) or key not in part:
            continue
        value = part.pop(key)
        for new_sec, new_key in targets:
            target = moved.setdefault(new_sec, {})
            if not isinstance(target, dict):
                continue  # the type check of from_dict reports it
            if (new_sec, new_key) in explicit:
                if target[new_key] != value and new_key == key:
                    raise ConfigError(f"{sec}.{key} is now {new_sec}.{new_key}; this file sets both, "
                                      f"to {value!r} and {target[new_key]!r}: keep only "
                                      f"{new_sec}.{new_key}")
                continue
            target[new_key] = value
    return moved


def from_dict(cls, data: dict, prefix: str = ""):
    """Return an instance of dataclass ``cls`` from a (partial) dict, strict about keys and types (a
    ``PipelineConfig``'s older keys moved first, ``migrate``).
    """
    if cls is PipelineConfig and not prefix and isinstance(data, dict):
        data = migrate(data)
    hints = typing.get_type_hints(cls)
    names = {f.name for f in fields(cls) if f.init}
    base = cls()
    kwargs = {}
    for key, value in data.items():
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in names:
            raise ConfigError(f"{dotted}: unknown key; known keys here: {', '.join(sorted(names))}")
        tp = hints[key]
        if is_dataclass(tp) and isinstance(value, dict):
            # a partial nested object keeps the defaults of the keys it leaves out
            current = to_dict(getattr(base, key))
            current.update(value)
            value = current
        kwargs[key] = _convert(value, tp, dotted)
    try:
        return dataclasses.replace(base, **kwargs)
    except ConfigError as e:
        said = str(e)
        raise ConfigError(f"{prefix}: {said}" if prefix and not said.startswith(prefix + ":") else said) from None


def save_config(config: PipelineConfig, path: str | os.PathLike) -> Path:
    """Write ``config`` as JSON (atomically); return the path."""
    return io.write_json(path, to_dict(config))


def save_parts(config: PipelineConfig, path: str | os.PathLike, parts: "typing.Iterable[str]") -> Path:
    """Write ``parts`` of ``config`` (e.g. ``("perspective",)``) into the config file at ``path``,
    atomically. An existing file keeps its other parts (another tuner's) and is checked first: an
    invalid one raises ``ConfigError`` and is left as it is. A new file gets the whole config.
    """
    p = Path(path)
    if not p.exists():
        return save_config(config, p)
    load_config(p)  # refuse to merge into a file that is not a valid config
    held = io.read_json(p, "config file")
    held.update({part: to_dict(getattr(config, part)) for part in parts})
    return io.write_json(p, held)


def load_config(path: str | os.PathLike) -> PipelineConfig:
    """Read a PipelineConfig JSON file (keys left out keep their defaults)."""
    data = io.read_json(path, "config file")
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a config file holds a JSON object")
    try:
        return from_dict(PipelineConfig, data)
    except ConfigError as e:
        raise ConfigError(f"{path}: {e}") from None


PRESETS_DIR = Path(__file__).with_name("presets")


def preset_names() -> tuple[str, ...]:
    """Return the names of the bundled config presets (``lanelib/presets/<name>.json``)."""
    return tuple(sorted(p.stem for p in PRESETS_DIR.glob("*.json")))


def preset(name: str) -> PipelineConfig:
    """Return the bundled PipelineConfig preset ``name``, e.g. ``"p1"`` for the 960x540 Udacity P1 camera.

    Presets are partial JSON files in ``lanelib/presets/`` (an unknown name raises ``ConfigError``
    listing them). The road presets set the checks (``params.LaneChecks``) for a kind of road with
    the default camera; ``hard-roads`` and ``country`` switch on the opt-in hard-road parts
    (``docs/hard-roads.md``; off by default, as no real row of the scoreboard needs them):

    - ``highway``: the defaults, lanes of 3.0-4.5 m whose curvatures differ by at most 0.004 1/m (a
      measurement allowance: on 250 m+ curves a lane's lines differ by w / R**2 < 0.0001 1/m);
    - ``hard-roads``: the highway's checks and the hard-road parts;
    - ``country``: the hard-road parts, lanes of 2.5-5.0 m (rural lanes of 2.5-4.8 m, with 0.2 m of
      spread) and curvatures differing by up to 0.009 1/m: the highway's allowance plus w / R**2
      of a 4.8 m lane on a 30 m hairpin.
    """
    if name not in preset_names():
        raise ConfigError(f"no config preset {name!r}; bundled presets: {', '.join(preset_names())}")
    return load_config(PRESETS_DIR / f"{name}.json")


def preset_settings(name: str) -> tuple[str, ...]:
    """Return the ``"part.key=value"`` settings (``override``'s) that preset ``name`` makes, e.g.
    to switch the ``hard-roads`` parts on over another config.

    Examples
    --------
    >>> override(PipelineConfig(), preset_settings("hard-roads")) == preset("hard-roads")
    True
    """
    preset(name)  # an unknown name raises here, listing the presets
    data = json.loads((PRESETS_DIR / f"{name}.json").read_text(encoding="utf-8"))

    def flat(node: dict, prefix: str):
        for key, value in node.items():
            if isinstance(value, dict):
                yield from flat(value, f"{prefix}{key}.")
            else:
                yield f"{prefix}{key}={value if isinstance(value, str) else json.dumps(value)}"
    return tuple(flat(data, ""))


def load_config_or_preset(spec: str | os.PathLike) -> PipelineConfig:
    """Return the PipelineConfig in the JSON file ``spec``, or the bundled preset named ``spec`` (a
    file that exists wins).
    """
    path = Path(spec)
    if path.is_file():
        return load_config(path)
    if str(spec) in preset_names():
        return preset(str(spec))
    raise ConfigError(f"{spec}: no such config file and no bundled preset of that name; pass a "
                      f"PipelineConfig JSON file or a preset ({', '.join(preset_names())})")


def override(config: PipelineConfig, settings: "typing.Iterable[str]") -> PipelineConfig:
    """Return ``config`` with each ``"part.key=value"`` of ``settings`` set (the CLI's ``--set``).

    The key is dotted as in the JSON (``thresholds.yellow.open_px``); the value is read as JSON
    (``95``, ``true``, ``[3, 5]``), else as text (``thresholds.rule=yellow | white``). Types are
    checked as for a file; a malformed setting or unknown key raises ``ConfigError`` naming it and
    the keys known there.
    """
    data = to_dict(config)
    for setting in settings:
        path, sep, text = setting.partition("=")
        keys = path.strip().split(".")
        if not sep or not all(keys):
            raise ConfigError(f"--set {setting!r}: write it as part.key=value, e.g. "
                              "search.trim_outliers_pct=95")
        try:
            value = json.loads(text)
        except ValueError:
            value = {"True": True, "False": False}.get(text.strip(), text)
        node = data
        for depth, key in enumerate(keys[:-1]):
            child = node.get(key) if isinstance(node, dict) else None
            if not isinstance(child, dict):
                known = ", ".join(sorted(k for k, v in node.items() if isinstance(v, dict)))
                where = ".".join(keys[:depth]) or "the config"
                raise ConfigError(f"--set {setting!r}: {'.'.join(keys[:depth + 1])} is not a part of "
                                  f"{where}; its parts: {known or 'none (a plain value)'}")
            node = child
        if keys[-1] not in node:
            raise ConfigError(f"--set {setting!r}: {path.strip()} is not a key; known keys in "
                              f"{'.'.join(keys[:-1]) or 'the config'}: {', '.join(sorted(node))}")
        node[keys[-1]] = value
        try:
            data = to_dict(from_dict(PipelineConfig, data))
        except ConfigError as e:
            raise ConfigError(f"--set {setting!r}: {e}") from None
    return from_dict(PipelineConfig, data)
