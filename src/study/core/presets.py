"""The sizes a study runs at, by name: the one registry of every per-preset number, for the data, the runs, the
book and the command line.

A preset is a name (:data:`NAMES`), a line of help (:data:`HELP`) and its sizes (:data:`SIZES`): how many throws the
data set holds and for how long (``SynthConfig.preset`` reads ``"data"``), and how much of each experiment runs
(``study.runs.presets.Preset`` reads ``"runs"``; what a preset leaves out is the study's protocol, ``TrainConfig``'s
defaults). Each layer gives the numbers their types and defaults; this module holds the numbers. A new preset is
added here and nowhere else.
"""

from __future__ import annotations

from typing import Any

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


SIZES: dict[str, dict[str, dict[str, Any]]] = {
    # The whole book in minutes on the smoke dataset: 2 grid points, 2 seeds, 3 lengths, 3 epochs (of one step
    # each: the weights' average forgets fast).
    "smoke": {
        "data": {"n_train": 8, "n_test": 8, "duration": 3.0},
        "runs": {"length": 1.0, "lrs": (3e-3,), "truncations": (10, 30), "grid_seeds": (0, 1), "seeds": (0, 1),
                 "data_seeds": (0, 1), "lengths": (0.5, 1.0, 1.5), "length_seeds": (0, 1), "epochs": 3,
                 "patience": 2, "min_epochs": 2, "ema_decay": 0.5, "long_lengths": (1.5,), "protocol_seeds": (0,), "first_patience": 1,
                 "first_epochs": 2, "shape_train": 4, "shape_test": 4, "certify_per_class": 8,
                 "videos_per_class": 2, "real_clips": 2, "render_shadows": False},
    },
    # The paper's scale: 1000 + 1000 throws per class of 10 s; the grid is learning rate x truncation, 3 seeds a
    # point: the two LSTM cells at lr 1e-3 (at 3e-3 every one of their seeds stalled on the box-like priors, in
    # every build until the one that dropped it), the GRU at 1e-3 and 3e-3; Table 1 with 5 seeds; every other
    # accuracy over at least 3 (the training protocols, the length sweep); the long-memory test at 6 s. The protocol (epochs,
    # patience) is TrainConfig's own. The README gives the measured build time.
    "paper": {
        "data": {},
        "runs": {"lrs": (1e-3,), "cell_lrs": (("gru", (1e-3, 3e-3)),), "truncations": (30, 90),
                 "grid_seeds": (0, 1, 2), "seeds": (0, 1, 2, 3, 4), "data_seeds": (0, 1, 2),
                 "lengths": (0.5, 1.0, 2.0, 3.0, 6.0), "length_seeds": (0, 1, 2), "long_lengths": (6.0,),
                 "long_seeds": (0, 1, 2), "protocol_seeds": (0, 1, 2)},
    },
}
"""Preset -> ``{"data": SynthConfig fields, "runs": study.runs.presets.Preset fields}``: what differs from each
dataclass's defaults (the paper's data set is ``SynthConfig``'s defaults)."""


def sizes(name: str, part: str) -> dict[str, Any]:
    """The ``part`` (``"data"`` or ``"runs"``) of preset ``name``'s sizes; :class:`ConfigError` for an unknown
    preset."""
    return dict(SIZES[check(name)][part])


def check(name: str, what: str = "preset") -> str:
    """``name`` if it is a preset, else :class:`ConfigError` naming ``what`` and the presets allowed."""
    if name not in NAMES:
        raise ConfigError(f"{what} = {name!r} is unknown; use one of {', '.join(NAMES)}")
    return name


def describe() -> str:
    """``"'smoke' = ...; 'paper' = ..."``, for help texts."""
    return "; ".join(f"'{n}' = {HELP[n]}" for n in NAMES)
