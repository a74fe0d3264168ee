"""Experiments: the runs behind every table and figure of the book, on top of simulate, learn and see.

- ``presets``: how much of each experiment a preset runs;
- ``runs``: one trained run, cached by content, and many of them on a process pool or a Dask cluster;
- ``paper``: the configurations of the paper's experiments (grid, Table 1, protocols, ablation, lengths);
- ``runner``: :class:`Runner`, the object a chapter opens, whose methods are the experiments;
- ``stats``: means, spreads and 95 % intervals of groups of runs;
- ``cues``, ``realworld``, ``decide``: the cue chapter's, the real-world chapter's and the decision
  chapter's own computations.

``from study.experiments import Runner`` is all a chapter needs to start.
"""

from __future__ import annotations

from typing import Any

from study.experiments.presets import PRESETS, Preset, preset

__all__ = ["PRESETS", "Preset", "Runner", "preset"]


def __getattr__(name: str) -> Any:
    if name == "Runner":  # imported on first use: it brings torch, and the command line's help must not
        from study.experiments.runner import Runner

        return Runner
    raise AttributeError(f"module 'study.experiments' has no attribute {name!r}")
