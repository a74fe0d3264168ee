"""Content-addressed caches: stable hashes of what made a file, atomic writes, checksums.

A cache file is named by :func:`key` of everything that determines its content (config, seed, code
version, library versions). It is written to a temporary file in the same folder and renamed into
place, so a killed run never leaves a file that a later run would read as complete.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

PACKAGE_DIR = Path(__file__).resolve().parent


def canonical_json(obj: Any) -> str:
    """JSON with sorted keys and no whitespace: equal objects give equal strings."""

    def default(o: Any) -> Any:
        if dataclasses.is_dataclass(o) and not isinstance(o, type):
            return dataclasses.asdict(o)
        if isinstance(o, (np.integer, np.floating)):
            return o.item()
        if isinstance(o, np.ndarray):
            return o.tolist()
        if isinstance(o, Path):
            return str(o)
        raise TypeError(f"cannot hash an object of type {type(o).__name__}")

    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=default)


def key(obj: Any, length: int = 16) -> str:
    """A hex digest of ``obj``'s canonical JSON: the name of the cache entry it determines."""
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:length]


def source_hash(*module_names: str) -> str:
    """Hash of the source files of the named ``study`` modules (``"synth"``, or a file such as
    ``"peephole.cpp"``), or of all of them (every ``.py``, ``.cpp`` and ``.h`` file of the package).

    Part of every cache key, so a change to the code that made a file makes a new file.
    """
    names = module_names or tuple(sorted(p.stem if p.suffix == ".py" else p.name for p in PACKAGE_DIR.iterdir()
                                         if p.suffix in (".py", ".cpp", ".h")))
    h = hashlib.sha256()
    for name in names:
        h.update(name.encode())
        h.update((PACKAGE_DIR / (name if "." in name else f"{name}.py")).read_bytes())
    return h.hexdigest()[:16]


def array_checksum(arrays: Mapping[str, np.ndarray]) -> str:
    """SHA-256 over the names, dtypes, shapes and bytes of ``arrays``, in name order."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success, fsync it and rename it onto ``path``.

    On any exception the temporary file is removed and ``path`` is left as it was.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    write_bytes_atomic(path, text.encode())
