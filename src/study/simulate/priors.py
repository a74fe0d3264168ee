"""A priors file: the ranges a user's own data set is drawn from, read over a preset's and validated.

A TOML (or JSON) file with any of the sections ``light``, ``heavy`` (``study.simulate.config.ClassPrior``: mass
kg, log-uniform; restitution and friction, uniform) and ``launch`` (``LaunchPrior``: height m, horizontal and
vertical speed m/s, uniform; spin rad/s). A range is two numbers; what a file leaves out keeps the preset's
value::

    [light]
    mass = [0.05, 0.3]        # kg
    restitution = [0.5, 0.9]

    [heavy]
    mass = [5.0, 40.0]

    [launch]
    height = [0.8, 1.2]       # m

    cfg = read_priors("my-priors.toml", SynthConfig.preset("smoke"))

Every error names the file, the section and the field, and says what is allowed.
"""

from __future__ import annotations

import dataclasses
import json
import tomllib
from pathlib import Path
from typing import Any

from study.core.errors import ConfigError, DataError, check_file
from study.simulate.config import ClassPrior, LaunchPrior, SynthConfig

SECTIONS: dict[str, type] = {"light": ClassPrior, "heavy": ClassPrior, "launch": LaunchPrior}
"""The sections a priors file may have, each the dataclass its fields come from."""


def read_priors(path: str | Path, base: SynthConfig) -> SynthConfig:
    """``base`` with the ranges of the priors file at ``path`` (TOML, or JSON for a ``.json`` file) put over its
    own, validated. Raises :class:`DataError` for a file that is missing, empty or not TOML/JSON, and
    :class:`ConfigError` naming the section and field for anything else wrong in it."""
    p = check_file(path, "priors file", "write one as in study.simulate.priors (TOML sections light, heavy, launch)")
    text = p.read_text(encoding="utf-8", errors="replace")
    if not text.strip():
        raise DataError(f"priors file {p}: it is empty; give at least one of the sections {', '.join(SECTIONS)}")
    try:
        got = json.loads(text) if p.suffix.lower() == ".json" else tomllib.loads(text)
    except (ValueError, tomllib.TOMLDecodeError) as e:
        kind = "JSON" if p.suffix.lower() == ".json" else "TOML"
        raise DataError(f"priors file {p}: not {kind} ({e}); see study.simulate.priors for an example") from None
    if not isinstance(got, dict):
        raise ConfigError(f"priors file {p}: expected sections {', '.join(SECTIONS)}, got {type(got).__name__}")
    changes: dict[str, Any] = {}
    for section, values in got.items():
        if section not in SECTIONS:
            raise ConfigError(f"priors file {p}: unknown section [{section}]; use {', '.join(SECTIONS)}")
        if not isinstance(values, dict):
            raise ConfigError(f"priors file {p}: [{section}] must be a table of fields, not {values!r}")
        changes[section] = _section(p, section, values, getattr(base, section))
    try:
        return base.replace(**changes)
    except ConfigError as e:
        raise ConfigError(f"priors file {p}: {e}") from None


def _section(p: Path, section: str, values: dict[str, Any], current: Any) -> Any:
    """``current`` (a ClassPrior or LaunchPrior) with the file's ``values`` for it, each checked for shape."""
    fields = {f.name: f for f in dataclasses.fields(SECTIONS[section])}
    out = {}
    for name, v in values.items():
        if name not in fields:
            raise ConfigError(f"priors file {p}: [{section}] has no field {name!r}; use {', '.join(fields)}")
        is_range = isinstance(getattr(current, name), tuple)
        numbers = v if is_range else [v]
        if (not isinstance(numbers, list) or len(numbers) != (2 if is_range else 1)
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in numbers)):
            want = "two numbers [low, high]" if is_range else "a number"
            raise ConfigError(f"priors file {p}: [{section}] {name} = {v!r}; give {want}")
        out[name] = tuple(float(x) for x in numbers) if is_range else float(v)
    return dataclasses.replace(current, **out)
