"""Runs: training what the chapters ask for, cached by content, and the sizes a preset runs at.

- ``presets``: how much of each experiment a preset runs;
- ``records``: one trained run, cached by content (its record and its kept model);
- ``schedule``, ``cluster``: many runs at once on a process pool or a Dask cluster, and the build's plan;
- ``runtable``: runs as a table (:class:`~study.runs.runtable.Runs`);
- ``paper``: the paper's own numbers and the configurations of its experiments (grid, Table 1, lengths);
- ``stats``: means, spreads and 95 % intervals of groups of runs;
- ``runner``: :class:`Runner`, the object a chapter opens: its dataset, its runs, the grid and its winner.

``from study.runs import Runner`` is all a chapter needs to start.
"""

from __future__ import annotations

from typing import Any

from study.runs.presets import PRESETS, Preset, preset

__all__ = ["PRESETS", "Preset", "Runner", "preset"]


def __getattr__(name: str) -> Any:
    if name == "Runner":  # imported on first use: it brings torch, and the command line's help must not
        from study.runs.runner import Runner

        return Runner
    raise AttributeError(f"module 'study.runs' has no attribute {name!r}")
