"""The errors a user can fix, one class per kind of bad input.

Every error raised for bad input derives from :class:`StudyError`; its message names the file or the
parameter at fault and says what to do. The command line prints that message on one line and exits
with status 2.
"""

from __future__ import annotations

import math
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
