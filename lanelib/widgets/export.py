"""What a tuner writes and reads: the exported PNGs of what it shows, and the config file.

``Exports`` is a base class of ``base.Tuner`` that holds these methods apart from the tuner's
controls and preview. It uses only what every tuner has: the picked item (``images``,
``image``, ``is_video``, ``frame``), the views (``preview_sheet()``, ``annotated()``), the
config and its parts (``config``, ``parts``, ``shows``, ``set_config()``) and the readout
(``readout()``, ``message``, ``_show_error()``).
"""
from __future__ import annotations

import html
import os
from pathlib import Path

from .. import io
from ..config import PipelineConfig, from_dict, load_config, migrate, save_parts, to_dict
from ..data import repo_root
from ..errors import ConfigError, InputError, LaneLibError


class Exports:
    """The export, save and load of a ``Tuner``.

    ``export(folder, name)`` writes ``<name>_preview.png`` (``preview_sheet()``) and
    ``<name>_annotated.png`` (``annotated()``); ``write_preview(path)`` and
    ``write_annotated(path)`` write one of them. The ``export`` button beside the picker writes
    both to ``out/`` of the repository and lists them under the preview. ``save(path)`` writes
    the tuned parts into a config file, ``load(path)`` reads what the tuner shows from one.
    """

    def export_name(self) -> str:
        """Return the stem of the exported files: the picked file's name, the frame, the tuner.

        ``<file stem>_<tuner>`` for an image (``straight_1_threshold``), ``<file
        stem>_frame<index>_<tuner>`` for a video frame (``project_frame50_video``); the tuner
        is its class name without ``Tuner``, in lower case.
        """
        stem = self.images[self.image].stem
        frame = f"_frame{self.frame}" if self.is_video else ""
        kind = type(self).__name__.removesuffix("Tuner").lower() or "tuner"
        return f"{stem}{frame}_{kind}"

    def write_preview(self, path: str | os.PathLike) -> Path:
        """Write the preview sheet (``preview_sheet()``, full quality) to ``path``; return the path.

        PNG unless the suffix says otherwise (``io.IMAGE_SUFFIXES``); written atomically and
        never over the picked input.
        """
        target = self._export_target(path)
        return io.write_image(target, self.preview_sheet(), inputs=[self.images[self.image]])

    def write_annotated(self, path: str | os.PathLike) -> Path:
        """Write the annotated frame (``annotated()``) to ``path``; return the path.

        PNG unless the suffix says otherwise (``io.IMAGE_SUFFIXES``): a PNG holds exactly the
        pixels the command line draws. Written atomically and never over the picked input.
        """
        target = self._export_target(path)
        return io.write_image(target, self.annotated(), inputs=[self.images[self.image]])

    def export(self, folder: str | os.PathLike | None = None, name: str | None = None) -> dict[str, Path]:
        """Write the preview and the annotated frame as PNG; return ``{"preview": path, "annotated": path}``.

        Parameters
        ----------
        folder : where to write (made if missing); default: ``out/`` of the repository
            (``data.repo_root()``).
        name : the files' stem, ``<name>_preview.png`` and ``<name>_annotated.png``; default
            ``export_name()`` (the picked file, the frame of a video, the tuner).

        Both targets are checked before either is written: a name that would write over the
        picked input raises ``InputError`` and nothing is written.
        """
        out = Path(folder) if folder is not None else repo_root() / "out"
        stem = name if name is not None else self.export_name()
        targets = {kind: self._export_target(out / f"{stem}_{kind}.png")
                   for kind in ("preview", "annotated")}
        return {"preview": self.write_preview(targets["preview"]),
                "annotated": self.write_annotated(targets["annotated"])}

    def save(self, path: str | os.PathLike) -> Path:
        """Write the tuned parts (``self.parts``) into the PipelineConfig JSON at ``path``; return it.

        A file that exists keeps every other part it holds (e.g. the perspective that
        ``PerspectiveTuner`` saved there) and is checked first: one that is not a valid config
        raises ``ConfigError`` and is left as it is. A new file gets the whole config, the file
        the CLI's ``--config`` reads. The file is replaced atomically.
        """
        return save_parts(self.config, path, self.parts)

    def load(self, path: str | os.PathLike) -> PipelineConfig:
        """Read a PipelineConfig JSON into the controls and the preview; return the new config.

        Every key the file holds in the parts the tuner shows (``self.shows``) replaces the
        tuner's value; what the file leaves out, and the parts the tuner does not show, keep the
        tuner's values.
        """
        load_config(path)  # the strict check, with the file's name in its errors
        held = migrate(io.read_json(path, "config file"))
        merged = to_dict(self.config)
        for part in self.shows:
            if part in held:
                merged[part] = _merged(merged[part], held[part])
        try:
            config = from_dict(PipelineConfig, merged)
        except ConfigError as e:
            raise ConfigError(f"{path}: {e}") from None
        self.set_config(config)
        return config

    def _export_target(self, path: str | os.PathLike) -> Path:
        """Return ``path`` as an export's target: an image suffix, not the picked input."""
        target = Path(path)
        if target.suffix.lower() not in io.IMAGE_SUFFIXES:
            raise InputError(f"{target}: an exported image needs an image suffix "
                             f"({', '.join(io.IMAGE_SUFFIXES)}); e.g. {target.name or 'view'}.png")
        io.check_not_input(target, [self.images[self.image]])
        return target

    def _on_export(self, button=None) -> None:
        """Export to ``out/`` and list the files under the preview (or say why it failed)."""
        try:
            written = self.export()
        except LaneLibError as e:
            self._show_error(str(e))
            return
        self.error = ""
        text = "\n".join(filter(None, [self.readout(), "exported: " + ", ".join(
            str(p) for p in written.values())]))
        self.message.value = f'<pre style="margin:0">{html.escape(text)}</pre>'


def _merged(mine, held):
    """Return ``mine`` (a part as plain dicts) with every key ``held`` sets replaced, recursively."""
    if not (isinstance(mine, dict) and isinstance(held, dict)):
        return held
    out = dict(mine)
    for k, v in held.items():
        out[k] = _merged(out[k], v) if k in out else v
    return out
