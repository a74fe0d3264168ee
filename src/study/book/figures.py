"""One matplotlib style for the whole book: colour-blind-safe colours, units on axes, stable files.

Chapters call :func:`use_style` once and colour the two classes with :data:`CLASS_COLORS`; the style fixes
the font and the SVG ids, so the same figure gives the same image. Nothing here selects a GUI backend: it
works under Agg (scripts, tests) and under the notebook's inline backend alike.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import matplotlib as mpl
from matplotlib.figure import Figure

from study.experiments.cues import Bin, Point, Sweep
from study.experiments import paper
from study.experiments.runtable import Runs
from study.experiments.stats import Summary

# Okabe & Ito (2008), "Color Universal Design": distinguishable with every common colour deficiency.
OKABE_ITO: dict[str, str] = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky_blue": "#56B4E9",
    "bluish_green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish_purple": "#CC79A7",
}

CLASS_COLORS: dict[str, str] = {"light": OKABE_ITO["blue"], "heavy": OKABE_ITO["vermillion"]}
"""Colour of each class in every figure: light (bouncy) blue, heavy (sliding) vermillion."""

# The colour cycle starts with the two class colours, so a plain two-line plot is already coded.
_CYCLE = [OKABE_ITO[k] for k in ("blue", "vermillion", "bluish_green", "orange", "reddish_purple", "sky_blue", "yellow", "black")]

STYLE: dict[str, Any] = {
    "axes.prop_cycle": mpl.cycler(color=_CYCLE),
    "axes.grid": True,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.titlesize": 11,
    "axes.labelsize": 10,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.6,
    "legend.frameon": False,
    "legend.fontsize": 9,
    "lines.linewidth": 1.4,
    "xtick.labelsize": 9,
    "ytick.labelsize": 9,
    "figure.figsize": (6.4, 3.6),
    "figure.dpi": 100,
    "figure.constrained_layout.use": True,
    "savefig.dpi": 150,
    "image.cmap": "cividis",
    "font.family": "DejaVu Sans",  # ships with matplotlib: the same glyphs on every machine
    "svg.fonttype": "path",
    "svg.hashsalt": "study",  # fixed element ids instead of random ones
}
"""The rcParams every figure of the book is drawn with."""

def use_style() -> None:
    """Apply :data:`STYLE` to matplotlib's global rcParams (call once at the top of a chapter)."""
    mpl.rcParams.update(STYLE)


DIMS_NAMES = paper.DIMS_NAMES
"""The inputs' names (their one home is ``study.experiments.paper``)."""
DIMS_COLORS = {"xyz": OKABE_ITO["blue"], "z": OKABE_ITO["orange"]}
"""Colour of each input in every figure that compares them."""


def accuracy_vs_length(summary: Sequence[Summary], runs: Runs, long_summary: Sequence[Summary] = ()) -> Figure:
    """The paper's Figure 4, ours: test accuracy against input length, one panel per input (X, Y, Z; Z).

    ``summary``: ``study.experiments.stats.summarise(runs, ("dims", "length"))`` (mean and 95 % interval,
    drawn as a line and a band); ``runs``: the single runs (dots; a cross for a run that failed to
    train); ``long_summary``: the long-memory variant's summary, drawn as open diamonds with error bars.
    (``study.experiments.length.Sweep`` holds all three.)
    """
    import matplotlib.pyplot as plt

    def of(groups: Sequence[Summary], d: str) -> list[Summary]:
        return sorted((g for g in groups if g.keys["dims"] == d), key=lambda g: g.keys["length"])

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    for ax, d in zip(axes, ("xyz", "z")):
        c = DIMS_COLORS[d]
        s = of(summary, d)
        L = [g.keys["length"] for g in s]
        ax.fill_between(L, [100 * g.interval.lo for g in s], [100 * g.interval.hi for g in s],  # type: ignore[union-attr]
                        color=c, alpha=0.2, linewidth=0)
        ax.plot(L, [100 * g.mean for g in s], "o-", color=c, label="paper's network (mean, 95 % CI)")
        for failed, marker, colour in ((False, ".", c), (True, "x", "black")):
            pts = runs.where(dims=d, failed=failed)
            ax.plot(pts.values("length"), 100 * pts.accuracies(), marker, color=colour,
                    alpha=0.5 if not failed else 1.0, markersize=7 if failed else 5,
                    label=f"failed to train ({len(pts)} runs)" if failed else None)
        m = of(long_summary, d)
        if m:
            ax.errorbar([g.keys["length"] for g in m], [100 * g.mean for g in m],
                        yerr=[[100 * (g.mean - g.interval.lo) for g in m],  # type: ignore[union-attr]
                              [100 * (g.interval.hi - g.mean) for g in m]],  # type: ignore[union-attr]
                        fmt="D", markerfacecolor="none", color="black", capsize=3,
                        label="memory that spans the input (chrono, full BPTT)")
        ax.axhline(50, color="0.5", linestyle=":", linewidth=1, label="chance")
        ax.set(title=DIMS_NAMES[d], xlabel="input length T (s)")
    axes[0].set_ylabel("test accuracy (%)")
    axes[0].legend(fontsize=8, loc="lower left")
    return fig


def robustness_curves(points: Sequence[Point], sweeps: Mapping[str, Sweep], marks: Mapping[str, float],
                      groups: Mapping[str, str]) -> Figure:
    """One panel per sweep of ``study.experiments.cues.robustness``: accuracy (mean, 95 % band) of each model group
    (``groups``: its key -> its legend) against the sweep's values, a dotted line at ``marks[sweep]`` (the
    calibrated or exact value)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(11, 6), sharey=True)
    colours = [OKABE_ITO["orange"], OKABE_ITO["bluish_green"], OKABE_ITO["reddish_purple"]]
    for ax, (name, sweep) in zip(axes.ravel(), sweeps.items()):
        for (group, legend), colour in zip(groups.items(), colours):
            pts = [r for r in points if r.sweep == name and r.group == group]
            v = [r.value for r in pts]
            ax.fill_between(v, [100 * r.interval.lo for r in pts], [100 * r.interval.hi for r in pts],
                            color=colour, alpha=0.2, linewidth=0)
            ax.plot(v, [100 * r.interval.value for r in pts], "o-", color=colour, label=legend)
        ax.axvline(marks[name], color="black", ls=":", lw=1)
        ax.axhline(50, color="0.5", ls=":", lw=1)
        ax.set(xlabel=sweep.label)
    for ax in axes[:, 0]:
        ax.set_ylabel("test accuracy (%)")
    axes[0, 0].legend(fontsize=8)
    return fig


def accuracy_by_parameter(curves: Mapping[tuple[str, str], Sequence[Bin]], names: tuple[str, ...]) -> Figure:
    """Accuracy against each throw parameter (``study.experiments.cues.by_parameter`` bins under
    ``curves[(name, dims)]``), one panel per parameter, a line per class and input (solid X, Y, Z; dashed Z)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(names), figsize=(11, 3.2), sharey=True)
    for ax, name in zip(axes, names):
        for d, ls in (("xyz", "-"), ("z", "--")):
            for label, cname in enumerate(CLASS_COLORS):
                q = [r for r in curves[name, d] if r.label == label]
                ax.plot([r.centre for r in q], [100 * r.accuracy for r in q], ls, marker="o", ms=3,
                        color=CLASS_COLORS[cname], label=f"{cname}, {DIMS_NAMES[d]}")
        ax.set(xlabel=name + (" (kg, log scale)" if name == "mass" else ""), xscale="log" if name == "mass" else "linear")
    axes[0].set_ylabel("test accuracy (%)")
    axes[0].legend(fontsize=7)
    return fig
