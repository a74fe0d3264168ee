"""The model a book build recommends for a camera, kept in the data folder so that ``study classify`` can answer
without ``--model``.

The real-world chapter chooses it (``study.chapters.realworld.recommend``: the Z model with the best mean accuracy
over seeds on validation throws as a user's own camera gives them) and :func:`save` writes ``recommended.json`` in
the build's data folder: the chosen candidate's name, its seeds' model folders (relative to the data folder, so
the folder can move), its validation accuracy and the preset. :func:`load` reads it back as one classifier, the
mean of its seeds' probabilities (``study.learn.trained.Ensemble``).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from study.core.cache import write_text_atomic
from study.core.errors import ModelError
from study.learn.metrics import Interval
from study.learn.trained import Ensemble

FILE = "recommended.json"
"""Its name in the data folder."""
FORMAT = "study.recommended/1"


@dataclass(frozen=True)
class Recommended:
    """What ``recommended.json`` says."""

    name: str
    """The chosen candidate (``"positions, randomised"`` and so on)."""
    models: tuple[Path, ...]
    """Its seeds' model folders."""
    val: Interval
    """Its mean validation accuracy over those seeds, on throws as a user's own camera gives them."""
    preset: str
    """The preset of the build that chose it."""

    def describe(self) -> str:
        """One line: which model, from which build, how good on validation."""
        return (f"the {self.preset} build's recommended model ({self.name}, {len(self.models)} seeds; "
                f"{100 * self.val.value:.1f} % on validation throws as a user's camera gives them)")


def save(data_dir: str | Path, name: str, model_dirs: Sequence[Path], val: Interval, preset: str) -> Path:
    """Write ``data_dir/recommended.json`` (atomically) and return its path."""
    root = Path(data_dir).resolve()
    dirs = [Path(d).resolve() for d in model_dirs]
    rel = [str(d.relative_to(root) if d.is_relative_to(root) else d) for d in dirs]
    body = {"format": FORMAT, "name": name, "models": rel, "preset": preset, "val": dataclasses.asdict(val)}
    path = Path(data_dir) / FILE
    write_text_atomic(path, json.dumps(body, indent=1) + "\n")
    return path


def read(data_dir: str | Path) -> Recommended:
    """What ``data_dir/recommended.json`` says; :class:`ModelError` saying how to make one if there is none or it
    cannot be read."""
    path = Path(data_dir) / FILE
    if not path.is_file():
        raise ModelError(f"no --model given and no recommended model in {Path(data_dir)}: build the book there "
                         "('make book'; a book built with --data-dir DIR keeps it in DIR: pass the same --data-dir), "
                         "or train a Z model with 'study train --dims z --out DIR' and pass --model DIR")
    try:
        body = json.loads(path.read_text())
        if body.get("format") != FORMAT:
            raise ValueError(f"format {body.get('format')!r}")
        val = Interval(**body["val"])
        models = tuple((Path(data_dir) / m) if not Path(m).is_absolute() else Path(m) for m in body["models"])
        if not models:
            raise ValueError("no models listed")
        return Recommended(str(body["name"]), models, val, str(body["preset"]))
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as e:
        raise ModelError(f"{path} cannot be read ({type(e).__name__}: {e}); build the book again to rewrite it, "
                         "or pass --model DIR") from None


def load(data_dir: str | Path) -> tuple[Ensemble, Recommended]:
    """The recommended model of the last build in ``data_dir`` as one classifier, and what its file says."""
    from study.learn import train

    rec = read(data_dir)
    for m in rec.models:
        if not m.is_dir():
            raise ModelError(f"{Path(data_dir) / FILE} names the model folder {m}, which is gone; build the book "
                             "again, or pass --model DIR")
    return Ensemble(tuple(train.load(m) for m in rec.models)), rec
