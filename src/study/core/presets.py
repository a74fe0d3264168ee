"""The sizes a study runs at, by name: one list for the data, the experiments, the book and the command line.

Each layer keeps its own values per preset (``SynthConfig.preset``, ``experiments.PRESETS``) and
checks its names against :data:`NAMES` (tested), so a new preset is added here first.
"""

from __future__ import annotations

from study.core.errors import ConfigError

NAMES: tuple[str, ...] = ("smoke", "paper")
"""Every preset, smallest first."""
DEFAULT = "paper"
"""The preset of ``make book`` and of every command that takes one."""
HELP: dict[str, str] = {
    "smoke": "tiny runs for tests and a quick look (minutes)",
    "paper": "the paper's scale: 1000 + 1000 trajectories per class, the full experiments",
}
"""One line per preset, for ``--help``."""


def check(name: str, what: str = "preset") -> str:
    """``name`` if it is a preset, else :class:`ConfigError` naming ``what`` and the presets allowed."""
    if name not in NAMES:
        raise ConfigError(f"{what} = {name!r} is unknown; use one of {', '.join(NAMES)}")
    return name


def describe() -> str:
    """``"'smoke' = ...; 'paper' = ..."``, for help texts."""
    return "; ".join(f"'{n}' = {HELP[n]}" for n in NAMES)
