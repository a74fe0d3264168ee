"""What the camera sweep measured for each kind of model through each path, and the copy of a paper build's that
ships with the package (:data:`SHIPPED`, written by ``scripts/shipped_measured.py`` from that build's results the
way ``scripts/readme_findings.py`` writes the README's findings), so that an answer in a clone that has built no
book still says how far to trust it. Light: ``study classify --help`` reads it without loading PyTorch.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from study.core.cache import write_text_atomic
from study.core.errors import ModelError
from study.learn.config import TrainConfig
from study.learn.metrics import Interval

SHIPPED = Path(__file__).with_name("measured.json")
"""The copy of a paper build's measurements shipped in the package (absent until one is written)."""
SHIPPED_FORMAT = "study.measured/1"

Measured = Mapping[str, Mapping[str, Interval]]
"""Kind of model (:func:`kind`) -> how the heights were had (``exact`` or a path's key,
``study.report.usercamera.SweepKey``) -> its accuracy on the camera sweep's clips, pooled, with its interval."""


def kind(cfg: TrainConfig) -> str:
    """A model's kind as the camera sweep tells them apart: what it reads and what it was trained on,
    ``"velocity-exact"``, ``"positions-any-camera"`` and so on (a model trained for the floor path is
    ``"…-randomised"`` by its config alone: :func:`candidate_kind` names it by what it was chosen for)."""
    return f"{cfg.inputs}-{cfg.observe}"


def candidate_kind(name: str) -> str:
    """The kind of a recommended model's candidate by its name (``study.methods.recommend.candidates``):
    ``"positions, floor"`` -> ``"positions-floor"``; for the other candidates what :func:`kind` of its config says."""
    return name.replace(", ", "-")


def measured_json(measured: Measured) -> dict[str, Any]:
    """``measured`` as JSON: kind -> path -> the interval's fields."""
    return {k: {p: dataclasses.asdict(iv) for p, iv in by_path.items()} for k, by_path in measured.items()}


def read_measured(body: Mapping[str, Any]) -> dict[str, dict[str, Interval]]:
    """:func:`measured_json`'s output read back."""
    return {str(k): {str(p): Interval(**iv) for p, iv in by_path.items()} for k, by_path in body.items()}


@dataclass(frozen=True)
class Shipped:
    """What a paper build measured, as shipped in the package (:data:`SHIPPED`)."""

    commit: str
    """The commit the build was made from."""
    preset: str
    """Its preset."""
    clips: int
    """The camera sweep's clips."""
    measured: Measured
    """Kind -> path -> accuracy on the sweep."""

    def source(self) -> str:
        return f"the {self.preset} build of {self.commit}, {self.clips} clips from random cameras"

    def span(self, path: str) -> str:
        """The lowest and highest accuracy of the kinds measured through ``path``, in words ('' if none)."""
        got = sorted(by[path].value for by in self.measured.values() if path in by)
        return "" if not got else f"{100 * got[0]:.1f}-{100 * got[-1]:.1f} %"


def write_shipped(path: str | Path, shipped: Shipped) -> Path:
    """Write ``shipped`` as JSON at ``path`` (atomically)."""
    body = {"format": SHIPPED_FORMAT, "commit": shipped.commit, "preset": shipped.preset, "clips": shipped.clips,
            "measured": measured_json(shipped.measured)}
    write_text_atomic(Path(path), json.dumps(body, indent=1) + "\n")
    return Path(path)


def read_shipped(path: str | Path | None = None) -> Shipped | None:
    """The shipped copy at ``path`` (default :data:`SHIPPED`); None if there is none. :class:`ModelError` if it
    cannot be read (a broken install: reinstall the package)."""
    path = Path(SHIPPED if path is None else path)
    if not path.is_file():
        return None
    try:
        body = json.loads(path.read_text())
        if body.get("format") != SHIPPED_FORMAT:
            raise ValueError(f"format {body.get('format')!r}")
        return Shipped(str(body["commit"]), str(body["preset"]), int(body["clips"]), read_measured(body["measured"]))
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as e:
        raise ModelError(f"{path} cannot be read ({type(e).__name__}: {e}); reinstall the package, or regenerate "
                         "it with scripts/shipped_measured.py from a paper build's results") from None
