"""Video files: open one for streaming decode with clear errors, and write one atomically.

Decoding never holds a whole video in memory: :func:`frames` yields one BGR frame at a time.
Writing goes to a hidden temporary file beside the target that is renamed into place on success,
so a failed or interrupted write never leaves a half-written video behind.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from study.core.errors import VideoError, check_writable

TRUNCATED_FRACTION = 0.9
"""A video that decodes fewer than this fraction of the frames its container lists is truncated."""


@dataclass(frozen=True)
class VideoInfo:
    """What the container says about a video."""

    path: Path
    """The video file."""
    fps: float
    """Frames per second as stored in the container."""
    width: int
    """Frame width, pixels."""
    height: int
    """Frame height, pixels."""
    frames: int
    """Frame count claimed by the container (may be wrong for a truncated file; 0 if unknown)."""


def _check_path(path: str | Path) -> Path:
    p = Path(path)
    if not p.exists():
        raise VideoError(f"video {p}: no such file; check the path")
    if not p.is_file():
        raise VideoError(f"video {p}: not a file; give a video file such as an .mp4")
    if p.stat().st_size == 0:
        raise VideoError(f"video {p}: the file is empty (0 bytes); re-record or re-copy it")
    return p


def open_video(path: str | Path) -> tuple[cv2.VideoCapture, VideoInfo]:
    """Open ``path`` for decoding; raise :class:`VideoError` if it is missing, empty or not a video."""
    p = _check_path(path)
    cap = cv2.VideoCapture(str(p))
    if not cap.isOpened():
        cap.release()
        raise VideoError(
            f"video {p}: OpenCV cannot decode it: not a video, or truncated (an .mp4 cut short loses its "
            "index); re-copy or re-encode it"
        )
    fps = float(cap.get(cv2.CAP_PROP_FPS))
    w = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH))
    h = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
    n = max(int(cap.get(cv2.CAP_PROP_FRAME_COUNT)), 0)
    if w <= 0 or h <= 0:
        cap.release()
        raise VideoError(f"video {p}: the container reports no frame size; the file is not a usable video")
    if not (fps > 0 and np.isfinite(fps)):
        cap.release()
        raise VideoError(f"video {p}: the container reports no frame rate; re-encode it with a fixed fps")
    return cap, VideoInfo(p, fps, w, h, n)


def probe(path: str | Path) -> VideoInfo:
    """The :class:`VideoInfo` of ``path`` (opens and closes it)."""
    cap, info = open_video(path)
    cap.release()
    return info


def stream(path: str | Path) -> tuple[VideoInfo, Iterator[np.ndarray]]:
    """Open ``path`` once: its :class:`VideoInfo` and an iterator over its frames, (H, W, 3) uint8 BGR.

    Streaming, constant memory. The iterator raises :class:`VideoError` (after the last frame) if no
    frame decodes, or far fewer than the container lists (a truncated file).
    """
    cap, info = open_video(path)

    def gen() -> Iterator[np.ndarray]:
        n = 0
        try:
            while True:
                ok, frame = cap.read()
                if not ok:
                    break
                n += 1
                yield frame
        finally:
            cap.release()
        if n == 0:
            raise VideoError(f"video {info.path}: no frame could be decoded; the file is empty or truncated")
        if info.frames > 0 and n < TRUNCATED_FRACTION * info.frames:
            raise VideoError(
                f"video {info.path}: truncated: decoded {n} of the {info.frames} frames the container lists; re-copy it"
            )

    return info, gen()


def frames(path: str | Path) -> Iterator[np.ndarray]:
    """Yield the frames of ``path`` one by one (see :func:`stream`)."""
    yield from stream(path)[1]


def read_frames(path: str | Path, indices) -> dict[int, np.ndarray]:
    """The frames at ``indices`` (0-based) of ``path`` as {index: (H, W, 3) uint8 RGB}, decoding in one pass."""
    want = set(int(i) for i in indices)
    out: dict[int, np.ndarray] = {}
    for i, frame in enumerate(frames(path)):
        if i in want:
            out[i] = np.ascontiguousarray(frame[:, :, ::-1])
        if len(out) == len(want):
            break
    return out


@contextlib.contextmanager
def atomic_writer(path: str | Path, fps: float, size: tuple[int, int], fourcc: str = "mp4v") -> Iterator[cv2.VideoWriter]:
    """Yield a ``cv2.VideoWriter`` (``size`` = (width, height)) writing to a temporary file renamed onto ``path``.

    The temporary file keeps ``path``'s extension so OpenCV picks the same container. On an
    exception it is removed and ``path`` is left as it was. :class:`OutputError` if ``path`` cannot be written.
    """
    target = check_writable(path, "video")
    tmp = target.with_name(f".{target.stem}.{os.getpid()}.tmp{target.suffix}")
    writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*fourcc), float(fps), (int(size[0]), int(size[1])))
    if not writer.isOpened():
        tmp.unlink(missing_ok=True)
        raise VideoError(f"video {target}: OpenCV cannot write codec {fourcc!r} to a {target.suffix!r} file; use .mp4")
    try:
        yield writer
        writer.release()
        os.replace(tmp, target)
    finally:
        writer.release()
        tmp.unlink(missing_ok=True)
