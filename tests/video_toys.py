"""Videos made from other videos for the tests: a throw in another colour."""

from __future__ import annotations

from pathlib import Path

from study.see import video


def recoloured(src: Path, out: Path) -> Path:
    """A copy of the video ``src`` at ``out`` with its red and blue channels swapped: an orange object turns blue."""
    info = video.probe(src)
    with video.atomic_writer(out, info.fps, (info.width, info.height)) as w:
        for frame in video.frames(src):
            w.write(frame[:, :, ::-1].copy())
    return out
