"""The dataset: trajectories with labels, and its file format (one ``.npz``, validated when read).

A dataset file holds the arrays of both splits plus a JSON header with the config that made it, the
seed, the library versions, the cache key and a SHA-256 checksum of every array. :func:`load` checks
all of that and raises :class:`study.core.errors.DataError` naming the file and the fault.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from study import CLASSES
from study.core.cache import array_checksum, atomic_path
from study.core.errors import DataError, check_file

FORMAT = "study.dataset/1"
SPLITS = ("train", "test")


@dataclass(frozen=True)
class Split:
    """One split of the dataset: ``n`` trajectories of ``T`` frames.

    Example::

        mine = study.Split(x=positions, y=labels)          # (n, T, 3) metres, (n,) 0/1
        ds = study.Dataset(train=mine, test=held_out, fps=30.0)
    """

    x: np.ndarray
    """(n, T, 3) float32, metres: world x, y, z of the object's centre; z is height above the ground."""
    y: np.ndarray
    """(n,) int64 labels: 0 = light (safe to pass over), 1 = heavy (must avoid); see ``study.CLASSES``."""
    params: dict[str, np.ndarray] = field(default_factory=dict)
    """Per-trajectory physical parameters and initial state, each (n,) or (n, k) float64."""

    def __len__(self) -> int:
        return int(self.y.shape[0])


@dataclass(frozen=True)
class Dataset:
    """Train and test splits sampled at ``fps`` frames per second, with their provenance.

    Example::

        ds = study.load_dataset("data/synth-<key>.npz")
        print(ds.fps, ds.train.x.shape, ds.test.y.mean())
    """

    train: Split
    test: Split
    fps: float
    """Frames per second of the trajectories."""
    meta: dict[str, Any] = field(default_factory=dict)
    """Provenance: config, seed, versions, key, checksum (as written in the file's header)."""
    path: Path | None = None
    """The file this dataset was read from or written to, if any."""

    @property
    def key(self) -> str:
        """Content key of the dataset (hash of config, seed and code version); '' if unknown."""
        return str(self.meta.get("key", ""))

    @property
    def n_frames(self) -> int:
        """T, the number of frames per trajectory."""
        return int(self.train.x.shape[1])

    @property
    def times(self) -> np.ndarray:
        """(T,) float64, seconds since recording started."""
        return np.arange(self.n_frames) / self.fps

    def split(self, name: str) -> Split:
        """The split called ``name`` ('train' or 'test')."""
        if name not in SPLITS:
            raise DataError(f"unknown split {name!r}; use one of {SPLITS}")
        return self.train if name == "train" else self.test


def _arrays(ds: Dataset) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name in SPLITS:
        s = ds.split(name)
        out[f"{name}/x"] = s.x
        out[f"{name}/y"] = s.y
        for k, v in s.params.items():
            out[f"{name}/params/{k}"] = v
    return out


def save(ds: Dataset, path: str | Path) -> Path:
    """Write ``ds`` to ``path`` atomically (temp file, fsync, rename) and return the path.

    Example::

        study.save_dataset(study.Dataset(train=mine, test=held_out, fps=30.0), "my-throws.npz")
    """
    arrays = _arrays(ds)
    meta = dict(ds.meta, format=FORMAT, fps=ds.fps, classes=list(CLASSES), checksum=array_checksum(arrays))
    path = Path(path)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, __meta__=np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8), **arrays)
    return path


def _is_text(p: Path) -> bool:
    """Whether the file's first bytes read as UTF-8 text (a CSV, say), for the error that says what it is."""
    with open(p, "rb") as f:
        head = f.read(512)
    try:
        head.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


def load(path: str | Path) -> Dataset:
    """Read and validate a dataset file written by :func:`save`.

    Raises :class:`DataError` if the file is missing, empty, not a dataset, truncated, or if any array
    does not match the checksum in its header.
    Example::

        ds = study.load_dataset("my-throws.npz")
    """
    hint = (f"write it again with `study synth --out {path}` (a cache in the data folder: delete it, the build makes it "
            "again; trajectories of your own: `study.simulate.data.save`)")
    p = check_file(path, "dataset", hint)
    if not zipfile.is_zipfile(p) and _is_text(p):
        raise DataError(f"dataset {p}: a text file, not a data set (a .npz archive written by `study synth` or "
                        "`study.simulate.data.save`); a trajectory CSV is read by `study classify CSV`")
    try:
        with np.load(p, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except (zipfile.BadZipFile, ValueError, OSError, EOFError, KeyError) as e:
        raise DataError(f"dataset {p}: cannot be read ({type(e).__name__}: {e}); {hint}") from None
    raw = arrays.pop("__meta__", None)
    if raw is None:
        raise DataError(f"dataset {p}: no header; not a study dataset; {hint}")
    try:
        meta = json.loads(raw.tobytes().decode())
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise DataError(f"dataset {p}: the header is corrupt; {hint}") from None
    if meta.get("format") != FORMAT:
        raise DataError(f"dataset {p}: format {meta.get('format')!r}, expected {FORMAT!r}; {hint}")
    if array_checksum(arrays) != meta.get("checksum"):
        raise DataError(f"dataset {p}: the arrays do not match the checksum in the header (corrupt or edited); {hint}")
    splits = {}
    for name in SPLITS:
        try:
            x, y = arrays[f"{name}/x"], arrays[f"{name}/y"]
        except KeyError:
            raise DataError(f"dataset {p}: the {name} split is missing; {hint}") from None
        if x.ndim != 3 or x.shape[2] != 3 or y.shape != (x.shape[0],):
            raise DataError(f"dataset {p}: {name} arrays have shapes {x.shape} and {y.shape}; expected (n, T, 3) and (n,); {hint}")
        prefix = f"{name}/params/"
        params = {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}
        splits[name] = Split(x=x, y=y, params=params)
    return Dataset(train=splits["train"], test=splits["test"], fps=float(meta["fps"]), meta=meta, path=p)
