"""Content-addressed caches: stable hashes of what made a file, atomic writes, checksums.

A cache file is named by :func:`key` of everything that determines its content (config, seed, code
version, library versions). It is written to a temporary file in the same folder and renamed into
place, so a killed run never leaves a file that a later run would read as complete.
"""

from __future__ import annotations

import ast
import contextlib
import dataclasses
import functools
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


def source_hash(*names: str, root: Path = PACKAGE_DIR, words: bool = False) -> str:
    """Hash of the named source files of the package, or of all of them (:func:`source_files`), each as its code
    alone (:func:`code_digest`: a Python module's syntax tree without its comments and docstrings).

    A name is a module relative to the package (``"simulate.synth"``) or a file path relative to it
    (``"learn/peephole.cpp"``). Part of every cache key, so a change to the code that made a file makes
    a new file, and a change to its words does not; with ``words``, the files' bytes, words included (what the book's
    builder keys a chapter's execution by: its text may quote a docstring). ``root``: the package folder (for tests
    on a copy of it).
    """
    paths = [n if "/" in n or n.endswith(SOURCE_SUFFIXES) else n.replace(".", "/") + ".py" for n in names]
    h = hashlib.sha256()
    for rel in paths or source_files(root):
        h.update(rel.encode())
        h.update((root / rel).read_bytes() if words else code_digest(root / rel))
    return h.hexdigest()[:16]


class _NoDocstrings(ast.NodeTransformer):
    """Drops every statement that is a bare string (docstrings, and the attribute docstrings under fields and
    constants): it computes nothing."""

    def generic_visit(self, node: ast.AST) -> ast.AST:
        super().generic_visit(node)
        for name in ("body", "orelse", "finalbody"):
            body = getattr(node, name, None)
            if isinstance(body, list) and body and all(isinstance(s, ast.stmt) for s in body):
                kept = [s for s in body if not (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant)
                                                and isinstance(s.value.value, str))]
                setattr(node, name, kept or ([ast.Pass()] if name == "body" and not isinstance(node, ast.Module)
                                             else kept))
        return node


def code_digest(path: Path) -> bytes:
    """What of the source file ``path`` can change a result, as a digest: a Python module's syntax tree without
    comments, docstrings or layout; any other file's bytes (the compiled loops' sources)."""
    st = path.stat()
    return _code_digest(path, st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=1024)
def _code_digest(path: Path, mtime_ns: int, size: int) -> bytes:
    if path.suffix != ".py":
        return hashlib.sha256(path.read_bytes()).digest()
    tree = _NoDocstrings().visit(ast.parse(path.read_text(), filename=str(path)))
    return hashlib.sha256(ast.dump(tree, annotate_fields=False, include_attributes=False).encode()).digest()


def array_checksum(arrays: Mapping[str, np.ndarray]) -> str:
    """SHA-256 over the names, dtypes, shapes and bytes of ``arrays``, in name order."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def umask_mode(directory: bool = False) -> int:
    """The permissions a plain ``open`` (or ``mkdir``) would give a new file (folder) under the process's umask:
    ``0o666 & ~umask`` (``0o777`` for a folder). ``tempfile`` makes its files 600 and folders 700 whatever the
    umask; what this module renames into place gets these instead, so a shared data folder stays shared."""
    mask = os.umask(0)
    os.umask(mask)
    return (0o777 if directory else 0o666) & ~mask


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
        os.chmod(tmp, umask_mode())
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def one_maker(path: str | Path) -> Iterator[None]:
    """Hold an exclusive lock on ``path``'s lock file (``<path>.lock``) while making ``path``: two processes that
    need the same cache entry at once (two chapters of a build) make it once; the second waits, then reads it.
    A folder where no lock can be taken (no ``fcntl``; read-only) makes it without one."""
    try:
        import fcntl
    except ImportError:  # not POSIX: each process may make it; the atomic rename keeps it whole
        yield
        return
    lock = Path(f"{path}.lock")
    try:
        lock.parent.mkdir(parents=True, exist_ok=True)
        f = open(lock, "a")  # noqa: SIM115 (held across the yield)
    except OSError:
        yield
        return
    try:
        fcntl.flock(f, fcntl.LOCK_EX)
        yield
    finally:
        f.close()  # releases the lock


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


# ---------------------------------------------------------------------------------------------
# Keys from the code itself: the import closure of whatever produced a file

EXEMPT: dict[str, str] = {
    "core/errors.py": "the errors a user can fix: what is raised and how it reads, never what is computed",
    "core/progress.py": "progress on the terminal: what is shown while a product is made, not the product",
    "core/ticket.py": "where a chapter in a build writes its progress, numbers and plan (the device, which a run's key "
                      "names itself, passes through it): never what is computed",
    "core/datadir.py": "where the caches are kept, never what is in them",
}
"""Modules whose source is left out of every code key, each with the reason it cannot change a result."""
NON_PYTHON: dict[str, tuple[str, ...]] = {
    "learn/native.py": ("learn/peephole.cpp", "learn/gru.cpp", "learn/rnn_math.h"),
}
"""Source files that a module builds from rather than imports (the compiled time loops), hashed with it."""
PRODUCERS: dict[str, tuple[str, tuple[str, ...]]] = {
    "run": ("study.runs.records", ()),
    "dataset-mujoco": ("study.simulate.mujoco_sim", ("simulate/synth.py",)),
    "dataset-bullet": ("study.simulate.bullet", ("simulate/synth.py",)),
    "video": ("study.methods.videos", ()),
    "tracker-error": ("study.methods.tracker", ()),
    "minirocket": ("study.methods.rockets", ()),
    "recommended": ("study.methods.recommend", ()),
}
"""Each cached product: the module whose function makes it, whose import closure its key hashes
(:func:`code_hash`), and files hashed with that closure but not followed. Runs and their models: the record a
run writes (``study.runs.records``) and the training behind it. A data set: its engine's simulation, and the
module that chooses the engine and writes the file (``simulate/synth.py``, which imports both engines: its own
source is hashed, not the other engine's)."""


def _module_file(module: str, root: Path) -> Path | None:
    """The source file of ``study.<...>`` module ``module`` (a package: its ``__init__.py``), or None."""
    parts = module.split(".")[1:]
    base = root.joinpath(*parts)
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _imported(path: Path, module: str, root: Path) -> set[str]:
    """The ``study`` modules a source file imports, read from its syntax tree (function-local imports and the
    packages a submodule's import runs included); parsed once per version of the file."""
    st = path.stat()
    return set(_imported_cached(path, module, root, st.st_mtime_ns, st.st_size))


@functools.lru_cache(maxsize=1024)
def _imported_cached(path: Path, module: str, root: Path, mtime_ns: int, size: int) -> frozenset[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            found.add(base)
            found.update(f"{base}.{a.name}" for a in node.names)  # a submodule, if it is one
    out = set()
    for name in found:
        if name != "study" and not name.startswith("study."):
            continue
        parts = name.split(".")
        for i in range(1, len(parts) + 1):  # the packages on the way run their __init__
            prefix = ".".join(parts[:i])
            if _module_file(prefix, root) is not None:
                out.add(prefix)
    return frozenset(out)


def closure(module: str, root: Path = PACKAGE_DIR) -> list[str]:
    """Every source file (relative, as :func:`source_hash` names them) that ``module`` (``"study.learn.train"``)
    imports, transitively, itself included, in sorted order; with the non-Python files they build from
    (:data:`NON_PYTHON`) and without the exempt ones (:data:`EXEMPT`)."""
    if _module_file(module, root) is None:
        raise ValueError(f"closure: no module {module!r} under {root}")
    seen: set[str] = set()
    todo = [module]
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.add(m)
        path = _module_file(m, root)
        if path is not None:
            todo.extend(_imported(path, m, root) - seen)
    files = set()
    for m in seen:
        path = _module_file(m, root)
        if path is None:
            continue
        rel = path.relative_to(root).as_posix()
        files.add(rel)
        files.update(NON_PYTHON.get(rel, ()))
    return sorted(f for f in files if f not in EXEMPT)


def code_hash(product: str, root: Path = PACKAGE_DIR) -> str:
    """The hash of the code behind ``product`` (a key of :data:`PRODUCERS`): every file of its producer's import
    closure. Part of that product's cache key, so an edit anywhere in that code makes new files, and an edit
    elsewhere does not."""
    if product not in PRODUCERS:
        raise ValueError(f"code_hash: unknown product {product!r}; name its producer in study.core.cache.PRODUCERS")
    module, files = PRODUCERS[product]
    return source_hash(*sorted(set(closure(module, root)) | set(files)), root=root)
