"""The models a book build recommends for a camera, kept in the data folder so that ``study classify`` can answer
without ``--model``: saved and loaded here, chosen elsewhere (``study.methods.recommend``, a step the book's builder
runs once the chapters' runs are trained; never a side effect of executing a page).

``recommended.json`` holds one model per *camera path*, the way a video's pixels become heights (:data:`PATHS`:
``one-scale``, one scale per clip from the object's size; ``floor``, the camera floor marks give), each with

- the chosen candidate's name and its seeds' model folders (relative to the data folder, so the folder can move);
- its validation accuracy, and the accuracies the study measured for it on video (by path, each an interval:
  what an answer can quote);
- a *cannot-tell* band of p(heavy) (``None`` until one is certified), inside which an answer says it cannot tell;

and what the camera sweep measured for every kind of model it scored (:func:`kind`: what it reads and what it was
trained on) through every path, and the preset and the content key of the step that wrote it (the candidates' run
keys, the sweep's numbers and its code), so the builder can tell that it is up to date. :func:`load` reads one
path's model back as one classifier, the mean of its seeds' probabilities (``study.learn.trained.Ensemble``).

A copy of what a paper build measured ships with the package (``study.runs.measured``).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from study.core.cache import write_text_atomic
from study.core.errors import ModelError
from study.learn.metrics import Interval
from study.learn.trained import Ensemble
from study.runs.measured import Measured, measured_json, read_measured

FILE = "recommended.json"
"""Its name in the data folder."""
FORMAT = "study.recommended/2"
FORMATS = ("study.recommended/1", FORMAT)
"""Every format this code reads: format 1 held one model (the one-scale path's) and no accuracies on video."""
ONE_SCALE = "one-scale"
"""The camera path of a video read by one scale per clip (``study classify`` without a floor)."""
FLOOR = "floor"
"""The camera path of a video whose camera floor marks give (``study classify --floor``)."""
PATHS: tuple[str, ...] = (ONE_SCALE, FLOOR)
"""The camera paths a recommended model can serve."""


@dataclass(frozen=True)
class PathModel:
    """The model recommended for one camera path, and what the study measured of it."""

    name: str
    """The chosen candidate (``"positions, any-camera"`` and so on)."""
    models: tuple[Path, ...]
    """Its seeds' model folders."""
    val: Interval
    """Its mean validation accuracy over those seeds, on throws as a user's own camera gives them."""
    accuracy: Mapping[str, Interval] = field(default_factory=dict)
    """What the study measured for it on video, by how the heights were had (``exact``, and each path's key)."""
    band: tuple[float, float] | None = None
    """p(heavy) from ``band[0]`` to ``band[1]``: the study cannot tell the classes apart there (None: no band)."""

    def as_json(self, root: Path) -> dict[str, Any]:
        dirs = [Path(d).resolve() for d in self.models]
        rel = [str(d.relative_to(root) if d.is_relative_to(root) else d) for d in dirs]
        return {"name": self.name, "models": rel, "val": dataclasses.asdict(self.val),
                "accuracy": {k: dataclasses.asdict(v) for k, v in self.accuracy.items()},
                "band": None if self.band is None else list(self.band)}


@dataclass(frozen=True)
class Recommended:
    """What ``recommended.json`` says."""

    preset: str
    """The preset of the build that chose it."""
    paths: Mapping[str, PathModel]
    """Camera path (:data:`PATHS`) -> its model."""
    key: str = ""
    """The content key of the step that wrote it ('' for a file of format 1)."""
    measured: Measured = field(default_factory=dict)
    """What the camera sweep measured for each kind of model it scored, through each path (empty for format 1)."""

    def path(self, name: str = ONE_SCALE) -> PathModel:
        """The model for camera path ``name``; :class:`ModelError` if this build recommended none for it."""
        if name not in self.paths:
            raise ModelError(f"the {self.preset} build recommends no model for the {name} path (it has: "
                             f"{', '.join(self.paths)}); build the book again, or pass --model DIR")
        return self.paths[name]

    def describe(self, name: str = ONE_SCALE) -> str:
        """One line: which model, from which build, how good on validation."""
        m = self.path(name)
        return (f"the {self.preset} build's recommended model ({m.name}, {len(m.models)} seeds; "
                f"{100 * m.val.value:.1f} % on validation throws as a user's camera gives them)")


def save(data_dir: str | Path, preset: str, paths: Mapping[str, PathModel], key: str = "",
         measured: Measured | None = None) -> Path:
    """Write ``data_dir/recommended.json`` (atomically) and return its path."""
    unknown = set(paths) - set(PATHS)
    if unknown:
        raise ValueError(f"recommended.save: unknown camera paths {sorted(unknown)}; known: {PATHS}")
    root = Path(data_dir).resolve()
    body = {"format": FORMAT, "preset": preset, "key": key,
            "paths": {k: m.as_json(root) for k, m in paths.items()}, "measured": measured_json(measured or {})}
    path = Path(data_dir) / FILE
    write_text_atomic(path, json.dumps(body, indent=1) + "\n")
    return path


def save_one(data_dir: str | Path, name: str, model_dirs: Sequence[Path], val: Interval, preset: str) -> Path:
    """:func:`save` of one model for the one-scale path."""
    return save(data_dir, preset, {ONE_SCALE: PathModel(name, tuple(Path(d) for d in model_dirs), val)})


def _path_model(body: Mapping[str, Any], data_dir: Path) -> PathModel:
    models = tuple((data_dir / m) if not Path(m).is_absolute() else Path(m) for m in body["models"])
    if not models:
        raise ValueError("no models listed")
    band = body.get("band")
    return PathModel(str(body["name"]), models, Interval(**body["val"]),
                     {k: Interval(**v) for k, v in body.get("accuracy", {}).items()},
                     None if band is None else (float(band[0]), float(band[1])))


def read(data_dir: str | Path) -> Recommended:
    """What ``data_dir/recommended.json`` says; :class:`ModelError` saying how to make one if there is none or it
    cannot be read."""
    path = Path(data_dir) / FILE
    if not path.is_file():
        raise ModelError(f"no --model given and no recommended model in {Path(data_dir)} (the data folder: "
                         "--data-dir, else $STUDY_DATA_DIR, else ./data of the folder you run from): the book build "
                         "makes it ('make book' in the repository keeps it in its data/; a build with --data-dir DIR "
                         "in DIR: pass the same --data-dir), or train a Z model fit for video with 'study train "
                         "--data FILE --dims z --observe any-camera --out DIR' and pass --model DIR")
    try:
        body = json.loads(path.read_text())
        if body.get("format") not in FORMATS:
            raise ValueError(f"format {body.get('format')!r}")
        if body["format"] == "study.recommended/1":
            paths = {ONE_SCALE: _path_model(body, Path(data_dir))}
        else:
            paths = {k: _path_model(v, Path(data_dir)) for k, v in body["paths"].items()}
        return Recommended(str(body["preset"]), paths, str(body.get("key", "")), read_measured(body.get("measured", {})))
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as e:
        raise ModelError(f"{path} cannot be read ({type(e).__name__}: {e}); build the book again to rewrite it, "
                         "or pass --model DIR") from None


def load(data_dir: str | Path, path: str = ONE_SCALE) -> tuple[Ensemble, Recommended]:
    """The model the last build in ``data_dir`` recommends for camera ``path``, as one classifier, and what its file
    says."""
    rec = read(data_dir)
    return ensemble(rec, data_dir, path), rec


def ensemble(rec: Recommended, data_dir: str | Path, path: str = ONE_SCALE) -> Ensemble:
    """The model ``rec`` (read from ``data_dir``) names for camera ``path``, its seeds loaded as one classifier."""
    from study.learn import train

    for m in rec.path(path).models:
        if not m.is_dir():
            raise ModelError(f"{Path(data_dir) / FILE} names the model folder {m}, which is gone; build the book "
                             "again, or pass --model DIR")
    return Ensemble(tuple(train.load(m) for m in rec.path(path).models))
