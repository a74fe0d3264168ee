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

from study.core.errors import output_error

PACKAGE_DIR = Path(__file__).resolve().parent.parent


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


SOURCE_SUFFIXES = (".py", ".cpp", ".h")
"""What counts as the package's source for :func:`source_hash`."""


def source_files(root: Path = PACKAGE_DIR) -> list[str]:
    """Every source file of the package under ``root``, subpackages included, as sorted relative paths."""
    return sorted(p.relative_to(root).as_posix() for p in root.rglob("*")
                  if p.suffix in SOURCE_SUFFIXES and p.is_file() and "__pycache__" not in p.parts)


def source_hash(*names: str, root: Path = PACKAGE_DIR) -> str:
    """Hash of the named source files of the package, or of all of them (:func:`source_files`).

    A name is a module relative to the package (``"simulate.synth"``) or a file path relative to it
    (``"learn/peephole.cpp"``). Part of every cache key, so a change to the code that made a file makes
    a new file. ``root``: the package folder (for tests on a copy of it).
    """
    paths = [n if "/" in n or n.endswith(SOURCE_SUFFIXES) else n.replace(".", "/") + ".py" for n in names]
    h = hashlib.sha256()
    for rel in paths or source_files(root):
        h.update(rel.encode())
        h.update((root / rel).read_bytes())
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

    On any exception the temporary file is removed and ``path`` is left as it was. A destination that
    cannot be written (its folder cannot be made, is read-only, lies under a file) raises
    :class:`study.core.errors.OutputError` naming it.
    """
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as e:
        raise output_error(target, e) from None
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


def subpackage_files(name: str, root: Path = PACKAGE_DIR) -> list[str]:
    """The source files of the subpackage ``name`` (``"see"``) as :func:`source_hash` names them."""
    return [f for f in source_files(root) if f.startswith(f"{name}/")]
