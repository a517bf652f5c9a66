"""Atomic output files: every output is written to a temporary file beside its target and renamed
into place, so an interrupted run never leaves a half-written output, and no output may
overwrite one of the run's inputs. Text and JSON outputs and the JSON reader live here too.
"""
from __future__ import annotations

import contextlib
import glob
import json
import os
import tempfile
from pathlib import Path
from typing import Iterable, Iterator

from ..errors import InputError


def check_not_input(target: str | os.PathLike, inputs: Iterable[str | os.PathLike]) -> None:
    """Raise InputError if ``target`` is the same file as one of ``inputs``."""
    t = Path(target).resolve()
    for i in inputs:
        if Path(i).resolve() == t:
            raise InputError(f"{target}: output would overwrite an input; choose another output path")



def check_output(target: str | os.PathLike, inputs: Iterable[str | os.PathLike] = (),
                 others: Iterable[str | os.PathLike] = ()) -> None:
    """Raise InputError if ``atomic_path`` could not write ``target`` (checked before any work): it is
    one of ``inputs`` (``check_not_input``) or ``others`` outputs, a folder, or its nearest existing
    parent is no writable folder.
    """
    t = Path(target)
    check_not_input(t, inputs)
    if any(Path(o).resolve() == t.resolve() for o in others):
        raise InputError(f"{t}: is another output of this command too; give each output its own path")
    if t.is_dir():
        raise InputError(f"{t}: is a folder; give a file path for this output")
    parent = t.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        why = "not a folder" if not parent.is_dir() else "not writable"
        raise InputError(f"{t}: cannot be written ({parent} is {why}); choose a writable output path")

def _temp_affixes(target: Path) -> tuple[str, str]:
    """Return the (prefix, suffix) of ``atomic_path``'s temporary files for ``target``."""
    return f".{target.stem}.", f".part{target.suffix}"


def remove_stale_temp_files(target: str | os.PathLike) -> list[Path]:
    """Remove and return the ``.<stem>.<random>.part<suffix>`` files of ``atomic_path`` that a process
    killed outright (SIGKILL, power loss) left beside ``target``; a resumed run calls it before
    writing ``target`` again (only its own writer makes such names).
    """
    t = Path(target)
    if not t.parent.is_dir():
        return []
    prefix, suffix = _temp_affixes(t)
    # mkstemp puts 8 random characters (letters, digits, _) between the prefix and the suffix
    stale = sorted(t.parent.glob(f"{glob.escape(prefix)}{'?' * 8}{glob.escape(suffix)}"))
    for f in stale:
        with contextlib.suppress(FileNotFoundError):
            f.unlink()
    return stale


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> Iterator[Path]:
    """Yield a temporary path beside ``target`` with its suffix (ffmpeg picks the container by it);
    rename it onto ``target`` when the block succeeds, remove it on any exception (Ctrl-C included).
    A folder that cannot be made or written to raises ``InputError``.
    """
    t = Path(target)
    check_not_input(t, inputs)
    try:
        t.parent.mkdir(parents=True, exist_ok=True)
        prefix, suffix = _temp_affixes(t)
        fd, tmp_name = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=t.parent)
    except OSError as e:
        raise InputError(f"{t}: cannot be written ({e.strerror or e}); choose a writable output "
                         "path") from None
    os.close(fd)
    tmp = Path(tmp_name)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; outputs get the usual permissions
    try:
        yield tmp
        os.replace(tmp, t)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def write_text(path: str | os.PathLike, text: str, inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write ``text`` to ``path`` atomically and return the path."""
    with atomic_path(path, inputs=inputs) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_json(path: str | os.PathLike, obj, inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write ``obj`` as indented JSON to ``path`` atomically and return the path."""
    return write_text(path, json.dumps(obj, indent=2) + "\n", inputs=inputs)


def read_json(path: str | os.PathLike, what: str = "JSON file"):
    """Return the parsed JSON at ``path``; a missing or malformed file raises InputError."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such {what}; check the path")
    try:
        return json.loads(p.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"{p}: not valid JSON ({e}); fix or regenerate the {what}") from None
    except OSError as e:
        raise InputError(f"{p}: cannot be read ({e.strerror or e}); check its permissions") from None
