"""The errors a user can fix, one class per kind of bad input.

Every error raised for bad input derives from :class:`StudyError`; its message names the file or the
parameter at fault and says what to do. The command line prints that message on one line and exits
with status 2.
"""

from __future__ import annotations

import contextlib
import math
import shutil
from collections.abc import Iterator
from pathlib import Path


class StudyError(Exception):
    """Base class: an error caused by the user's input, with a message that says how to fix it."""


class ConfigError(StudyError, ValueError):
    """A parameter is out of range, of the wrong type, or names an unknown preset or class."""


class DataError(StudyError):
    """A dataset or cache file is missing, truncated, corrupt, or does not match what it claims."""


class TrajectoryError(StudyError, ValueError):
    """A trajectory is unusable: NaN or infinite values, too short, or the wrong shape."""


class VideoError(StudyError):
    """A video file is missing, empty, truncated, or cannot be decoded."""


class TrackingError(StudyError):
    """The tracked object was never found, or found in too few frames to make a trajectory."""


class ModelError(StudyError):
    """A trained-model directory is missing a file or does not match the data it is used on."""


class RenderError(StudyError):
    """No OpenGL backend could be loaded for MuJoCo's renderer."""


class OutputError(StudyError):
    """A destination cannot be written: a folder that cannot be created, a read-only place, a path under a file."""


class ChapterError(StudyError):
    """A book chapter failed to execute; the message names the chapter and the cell."""


def check_range(
    name: str,
    value: float,
    lo: float = -math.inf,
    hi: float = math.inf,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> None:
    """Raise :class:`ConfigError` unless ``lo <= value <= hi`` (``<`` on an open end).

    ``name`` is the parameter as the user knows it (``"SynthConfig.duration"``), so the message can
    say exactly which field to change and to what.
    """
    ok_type = isinstance(value, (int, float)) and not isinstance(value, bool)
    if ok_type and math.isfinite(value):
        above = value > lo if lo_open else value >= lo
        below = value < hi if hi_open else value <= hi
        if above and below:
            return
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    raise ConfigError(f"{name} = {value!r} is out of range; allowed: {left}{lo}, {hi}{right}")


def check_file(path: str | Path, what: str, hint: str) -> Path:
    """Return ``path`` as a :class:`Path` if it is an existing non-empty file, else raise :class:`DataError`.

    ``what`` says what the file should be ("dataset"); ``hint`` says how to get one.
    """
    p = Path(path)
    if not p.exists():
        raise DataError(f"{what} {p}: no such file; {hint}")
    if not p.is_file():
        raise DataError(f"{what} {p}: not a file; {hint}")
    if p.stat().st_size == 0:
        raise DataError(f"{what} {p}: the file is empty; {hint}")
    return p


def output_error(path: str | Path, err: OSError, what: str = "output") -> OutputError:
    """The :class:`OutputError` for ``err``, raised while writing ``path``: names the path and what to do."""
    under_file = next((a for a in Path(path).parents if a.is_file()), None)
    reason = f"{under_file} is a file, not a folder" if under_file else (err.strerror or type(err).__name__)
    return OutputError(f"{what} {path}: cannot be written ({reason}); choose a folder you can write to")


def check_writable(path: str | Path, what: str = "output") -> Path:
    """Make sure a file can be written at ``path`` before long work starts; :class:`OutputError` if not.

    Creates the missing parent folders (as the write itself would) and a temporary file beside the
    target, which it removes; an existing file at ``path`` is left alone.
    """
    import tempfile

    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(prefix=f".{target.name}.", suffix=".probe", dir=target.parent):
            pass
    except OSError as e:
        raise output_error(target, e, what) from None
    if target.is_dir():
        raise OutputError(f"{what} {target}: is a folder; give a file name")
    return target


def _first_missing(path: Path) -> Path | None:
    """The topmost of ``path`` and its ancestors that does not exist yet (what writing ``path`` would create)."""
    missing = None
    for p in (path, *path.parents):
        if p.exists() or p.is_symlink():
            break
        missing = p
    return missing


@contextlib.contextmanager
def removed_on_error(*paths: str | Path | None) -> Iterator[None]:
    """Run the block; if it raises, remove whatever it created of ``paths`` (and of their missing parent
    folders): a command that fails leaves nothing behind. What existed before is never touched."""
    created = [m for p in paths if p is not None and (m := _first_missing(Path(p).absolute())) is not None]
    try:
        yield
    except BaseException:
        for m in created:
            if m.is_dir() and not m.is_symlink():
                shutil.rmtree(m, ignore_errors=True)
            else:
                with contextlib.suppress(OSError):  # nothing there, or a path under a file
                    m.unlink()
        raise
