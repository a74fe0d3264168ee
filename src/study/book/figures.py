"""One matplotlib style for the whole book: colour-blind-safe colours, units on axes, stable files.

Chapters call :func:`use_style` once and colour the two classes with :data:`CLASS_COLORS`; the style fixes
the font and the SVG ids, so the same figure gives the same image. Nothing here selects a GUI backend: it
works under Agg (scripts, tests) and under the notebook's inline backend alike.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import matplotlib as mpl
from matplotlib.figure import Figure

from study.runs import paper
from study.runs.runtable import Runs
from study.runs.stats import Summary

if TYPE_CHECKING:
    from study.chapters.cues import Bin, Point, Sweep

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
"""The inputs' names (their one home is ``study.runs.paper``)."""
DIMS_COLORS = {"xyz": OKABE_ITO["blue"], "z": OKABE_ITO["orange"]}
"""Colour of each input in every figure that compares them."""


def accuracy_vs_length(summary: Sequence[Summary], runs: Runs, long_summary: Sequence[Summary] = ()) -> Figure:
    """The paper's Figure 4, ours: test accuracy against input length, one panel per input (X, Y, Z; Z).

    ``summary``: ``study.runs.stats.summarise(runs, ("dims", "length"))`` (mean and 95 % interval,
    drawn as a line and a band); ``runs``: the single runs (dots; a cross for a run that failed to
    train); ``long_summary``: the long-memory variant's summary, drawn as open diamonds with error bars.
    (``study.chapters.length.Sweep`` holds all three.)
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
    """One panel per sweep of ``study.chapters.cues.robustness``: accuracy (mean, 95 % band) of each model group
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
    """Accuracy against each throw parameter (``study.chapters.cues.by_parameter`` bins under
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


def table1_runs(columns: Sequence[Any]) -> Figure:
    """Table 1 of the paper, ours, every run: one column per row of ``study.chapters.table1.Table1.figure``
    (a :class:`~study.chapters.table1.FigureRow` each), the paper's network left, beyond the paper right.

    In each column a dot per run (seed), the data sets side by side; the run validation picks on each data set
    ringed in black, a cross for a run that failed to train; our estimate as a black diamond with its 95 %
    interval; where the paper has a number, its line with the band ± its margin inside which ours reproduces it.
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    paper_colour = OKABE_ITO["reddish_purple"]
    panels = [([c for c in columns if c.paper is not None], "the paper's network (its Table 1)"),
              ([c for c in columns if c.paper is None], "beyond the paper")]
    panels = [(cols, title) for cols, title in panels if cols]
    fig, axes = plt.subplots(1, len(panels), figsize=(8.4, 4.8), sharey=True, squeeze=False,
                             width_ratios=[len(cols) for cols, _ in panels])
    for ax, (cols, title) in zip(axes[0], panels):
        for x, c in enumerate(cols):
            colour = DIMS_COLORS[c.dims]
            for j, runs in enumerate(c.runs):  # data set j: a strip left of the estimate
                at = x - 0.3 + (0.36 * j / (len(c.runs) - 1) if len(c.runs) > 1 else 0.18)
                for i, r in enumerate(runs):
                    if r.accuracy is None:
                        continue
                    dx = at + 0.03 * (i - (len(runs) - 1) / 2)
                    if r.failed:
                        ax.plot(dx, 100 * r.accuracy, "x", color="black", ms=6, zorder=3)
                    else:
                        ax.plot(dx, 100 * r.accuracy, "o", color=colour, alpha=0.6, ms=4.5, zorder=2)
                    if r.seed == c.picked[j]:  # ringed, whether it trained or not
                        ax.plot(dx, 100 * r.accuracy, "o", mfc="none", mec="black", mew=1.3, ms=9, zorder=3)
            e = c.estimate
            ax.errorbar(x + 0.28, 100 * e.value, [[100 * (e.value - e.lo)], [100 * (e.hi - e.value)]], fmt="D",
                        color="black", ms=6, capsize=3, zorder=4)
            if c.paper is not None:
                ax.add_patch(Rectangle((x - 0.45, 100 * (c.paper - c.margin)), 0.9, 200 * c.margin, color="0.88",
                                       lw=0, zorder=0))
                ax.plot([x - 0.45, x + 0.45], [100 * c.paper] * 2, color=paper_colour, lw=2.5, zorder=1)
        ax.axhline(50, color="0.5", ls=":", lw=1)
        labels = [c.label + (f"\n({c.estimate.verdict})" if c.estimate.verdict else "") for c in cols]
        ax.set_xticks(range(len(cols)), labels)
        ax.set(title=title, xlim=(-0.6, len(cols) - 0.4))
        ax.grid(axis="x", visible=False)
    axes[0, 0].set_ylabel("test accuracy (%)")
    handles = [Line2D([], [], ls="", marker="o", color=DIMS_COLORS["xyz"], alpha=0.6, ms=4.5, label="a run (X, Y, Z)"),
               Line2D([], [], ls="", marker="o", color=DIMS_COLORS["z"], alpha=0.6, ms=4.5, label="a run (Z only)"),
               Line2D([], [], ls="", marker="o", mfc="none", mec="black", mew=1.3, ms=9,
                      label="the run validation picks"),
               Line2D([], [], ls="", marker="x", color="black", ms=6, label="failed to train"),
               Line2D([], [], ls="", marker="D", color="black", ms=6, label="ours, 95 % CI"),
               Line2D([], [], color=paper_colour, lw=2.5, label="paper's best"),
               Patch(color="0.88", label="paper ± margin"),
               Line2D([], [], color="0.5", ls=":", lw=1, label="chance")]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=9)
    return fig


def methods_accuracy(rows: Sequence[Any]) -> Figure:
    """Every method of the chapter *What a practitioner would try first* on the same test split: one row per
    method (``study.chapters.baselines.Baselines.figure``), its mean test accuracy with the 95 % interval in
    each (input, positions) condition (X, Y, Z exact: filled circle; Z exact: filled square; Z observed by the
    calibrated tracker: open square)."""
    import matplotlib.pyplot as plt

    style = {("xyz", "exact"): ("o", DIMS_COLORS["xyz"], DIMS_COLORS["xyz"], "X, Y, Z, exact positions"),
             ("z", "exact"): ("s", DIMS_COLORS["z"], DIMS_COLORS["z"], "Z, exact positions"),
             ("z", "observed"): ("s", DIMS_COLORS["z"], "white", "Z, observed positions")}
    fig, ax = plt.subplots(figsize=(8, 0.55 * len(rows) + 1.4))
    for k, (cell, (marker, colour, face, label)) in enumerate(style.items()):
        ys, xs, lo, hi = [], [], [], []
        for i, r in enumerate(rows):
            n = r.accuracy.get(cell)
            if n is not None:
                ys.append(i + 0.22 * (k - 1))
                xs.append(100 * n.value)
                lo.append(100 * (n.value - n.lo))
                hi.append(100 * (n.hi - n.value))
        ax.errorbar(xs, ys, xerr=[lo, hi], fmt=marker, color=colour, mfc=face, mec=colour, mew=1.3, ms=6,
                    capsize=2.5, label=label)
    ax.axvline(50, color="0.5", ls=":", lw=1, label="chance")
    ax.set_yticks(range(len(rows)), [r.name for r in rows])
    ax.set(xlabel="test accuracy (%), mean over seeds with 95 % CI", ylim=(len(rows) - 0.5, -0.5))
    ax.grid(axis="y", visible=False)
    handles, labels = ax.get_legend_handles_labels()
    order = sorted(range(len(labels)), key=lambda i: labels[i] == "chance")  # the conditions first, chance last
    fig.legend([handles[i] for i in order], [labels[i] for i in order], loc="outside lower center", ncol=4,
               fontsize=9)
    return fig


VERDICT_STYLE: dict[str, tuple[str, str]] = {"reproduced": (OKABE_ITO["bluish_green"], "o"),
                                             "differs": (OKABE_ITO["vermillion"], "s"),
                                             "inconclusive": (OKABE_ITO["orange"], "D")}
"""Colour and marker of each verdict with a number (reproduced, differs, inconclusive): two cues, so the verdict
reads in grey or with any colour deficiency too."""

_UNIT_AXIS = {"fraction": "difference (accuracy points)", "count": "difference (bounces, a count)",
              "s": "difference (seconds)"}


def _rows_axis(ax: Any, labels: Sequence[str], above: float = 0.2) -> None:
    """A forest panel's rows, top down, each label written ``above`` (rows) over its row, so the panel's whole
    width stays for the data."""
    from matplotlib.transforms import blended_transform_factory

    at = blended_transform_factory(ax.transAxes, ax.transData)
    for y, label in enumerate(labels):
        ax.text(0.01, y - above, label, transform=at, fontsize=8.5, va="bottom", ha="left", clip_on=False)
    ax.set_yticks([])
    ax.set_ylim(len(labels) - 0.55, -0.75 - above)
    ax.grid(axis="y", visible=False)


def _interval(ax: Any, y: float, value: float, lo: float, hi: float, colour: str, marker: str, **kw: Any) -> None:
    """One estimate as a marker with its interval as a horizontal bar."""
    ax.errorbar(value, y, xerr=[[value - lo], [hi - value]], fmt=marker, color=colour, capsize=2.5, elinewidth=1.4,
                zorder=4, **{"ms": 6, **kw})


def forest(forest: Any) -> Figure:
    """The summary's first figure: the paper's numbers and claims against ours, one row each, a tall figure that
    reads on a phone. ``forest``: a :class:`study.book.summary.Forest`.

    Top, each number of the paper that has a margin: its value (a purple line) and its margin (a grey band, inside
    which ours reproduces it), ours as a marker with its 95 % interval. Below, each claimed order as our difference
    against 0 and ±δ (accuracy points), then one small panel per other unit (Figure 3's count and seconds, judged on
    the side of 0 alone). The marker's colour and shape is the verdict (:data:`VERDICT_STYLE`); the rows without a
    number to draw are named at the foot.
    """
    import textwrap

    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    paper_colour, band, delta_band = OKABE_ITO["reddish_purple"], "0.85", "0.92"
    orders = [tuple(m for m in forest.orders if m.number.unit == u) for u in forest.units]
    heights = [len(forest.numbers) + 1.3] + [len(g) + 1.5 for g in orders] + [1.6]
    fig = plt.figure(figsize=(4.4, 0.42 * sum(heights) + 1.0))
    axes = fig.subplots(len(heights), 1, height_ratios=heights)

    ax = axes[0]
    for y, m in enumerate(forest.numbers):
        s, p, mg = m.scale, m.paper, m.margin
        ax.add_patch(Rectangle((s * (p - mg), y - 0.32), 2 * s * mg, 0.64, color=band, lw=0, zorder=0))
        ax.plot([s * p] * 2, [y - 0.32, y + 0.32], color=paper_colour, lw=2.2, zorder=2)
        colour, marker = VERDICT_STYLE.get(m.verdict, ("black", "o"))
        _interval(ax, y, s * m.number.value, s * m.number.lo, s * m.number.hi, colour, marker)
    lo = min([50.0] + [m.scale * min(m.number.lo, m.paper - m.margin) for m in forest.numbers])
    hi = max([m.scale * max(m.number.hi, m.paper + m.margin) for m in forest.numbers] + [55.0])
    ax.axvline(50, color="0.5", ls=":", lw=1)
    ax.set(xlim=(max(0.0, lo - 3), min(100.0, hi + 3)), xlabel="test accuracy (%)")
    ax.set_title("The paper's numbers: ours with 95 % CI", loc="left", fontsize=10)
    _rows_axis(ax, [m.label for m in forest.numbers])

    for ax, unit, marks in zip(axes[1:], forest.units, orders):
        delta = max(m.scale * m.margin for m in marks)
        if delta > 0:
            ax.axvspan(-delta, delta, color=delta_band, lw=0, zorder=0)
        ax.axvline(0, color="black", lw=0.8, zorder=1)
        for y, m in enumerate(marks):
            colour, marker = VERDICT_STYLE.get(m.verdict, ("black", "o"))
            _interval(ax, y, m.scale * m.number.value, m.scale * m.number.lo, m.scale * m.number.hi, colour, marker)
        extent = max([delta] + [m.scale * max(abs(m.number.lo), abs(m.number.hi)) for m in marks])
        ax.set_xlim(-1.15 * extent, 1.15 * extent)
        ax.set_xlabel(_UNIT_AXIS.get(unit, f"difference ({unit})"))
        _rows_axis(ax, [f"{m.label} (paper: {'> 0' if m.sign > 0 else '< 0'})" for m in marks])
        if unit == "fraction":
            ax.set_title("The paper's orders: our difference, 95 % CI", loc="left", fontsize=10)

    foot = axes[-1]
    foot.axis("off")
    by: dict[str, list[str]] = {}
    for row, verdict in forest.unmarked:
        by.setdefault(verdict, []).append(row)
    text = "Without a marker: " + "; ".join(f"{', '.join(rows)} ({v})" for v, rows in by.items())
    foot.text(0, 1, textwrap.fill(text, 62), transform=foot.transAxes, va="top", fontsize=8)

    handles = [Line2D([], [], ls="", marker=mk, color=c, ms=6, label=v) for v, (c, mk) in VERDICT_STYLE.items()]
    handles += [Line2D([], [], color=paper_colour, lw=2.2, label="the paper's number"),
                Patch(color=band, label="± its margin"), Patch(color=delta_band, label="±δ: no difference"),
                Line2D([], [], color="0.5", ls=":", lw=1, label="chance")]
    fig.legend(handles=handles, loc="outside upper center", ncol=2, fontsize=8)
    return fig


def what_the_motion_allows(allows: Any) -> Figure:
    """The summary's second figure, what the study adds: for each condition the paper did not test (the camera's
    error, no air, the other engine) each learner's test accuracy with its 95 % interval, against the exact ceiling
    of the priors (dashed) and chance (dotted); ringed, the condition's best learner. ``allows``: a
    :class:`study.book.summary.Allows`. One panel per air setting, stacked, so it reads on a phone."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    from study.report.motion import SHOWN

    colour = {k: _CYCLE[i] for i, k in enumerate(SHOWN)}
    heights = [len(p.conditions) + 1.3 for p in allows.panels]
    fig = plt.figure(figsize=(4.4, 0.55 * sum(heights) + 1.9))
    axes = fig.subplots(len(heights), 1, height_ratios=heights, sharex=True)
    seen: dict[str, None] = {}
    lo = 50.0
    for ax, panel in zip(axes, allows.panels):
        for y, c in enumerate(panel.conditions):
            keys = list(c.accuracy)
            for i, k in enumerate(keys):
                n = c.accuracy[k]
                dy = 0.2 * (i - (len(keys) - 1) / 2)
                ring = {"mec": "black", "mew": 1.3, "ms": 8} if k == c.best else {}
                _interval(ax, y + dy, 100 * n.value, 100 * n.lo, 100 * n.hi, colour.get(k, "black"), "o", **ring)
                seen[k] = None
                lo = min(lo, 100 * n.lo)
        ax.axvline(100 * panel.ceiling.value, color="black", ls="--", lw=1.2)
        ax.axvline(50, color="0.5", ls=":", lw=1)
        ax.set_title(f"{panel.title} (ceiling {100 * panel.ceiling.value:.1f} %)", loc="left", fontsize=10)
        _rows_axis(ax, [c.label for c in panel.conditions], above=0.3)
    axes[-1].set(xlim=(max(0.0, lo - 3), 101), xlabel="test accuracy (%), 95 % CI")
    handles = [Line2D([], [], ls="", marker="o", color=colour.get(k, "black"), ms=6, label=allows.names[k]) for k in seen]
    handles += [Line2D([], [], ls="", marker="o", mfc="white", mec="black", mew=1.3, ms=8, label="best in its row"),
                Line2D([], [], color="black", ls="--", lw=1.2, label="exact ceiling of the priors"),
                Line2D([], [], color="0.5", ls=":", lw=1, label="chance")]
    fig.legend(handles=handles, loc="outside upper center", ncol=1, fontsize=8)
    return fig


def sample_trajectories(times: Any, x: Any, samples: Mapping[str, Sequence[int]]) -> Figure:
    """The paper's Figure 3: X, Y and Z against time for a few throws of each class, heavy on top as in the
    paper. ``times``: (T,) s; ``x``: (n, T, 3) metres; ``samples``: class name -> the throws' indices into ``x``."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(10, 5.4), sharex=True, squeeze=False)
    for row, name in enumerate(("heavy", "light")):
        for col, axis_name in enumerate("XYZ"):
            ax = axes[row, col]
            for j in samples[name]:
                ax.plot(times, x[j, :, col], lw=1.0, alpha=0.8, color=CLASS_COLORS[name])
            ax.set_title(f"{name}: {axis_name}")
            ax.set_ylabel(f"{axis_name.lower()}, m")
            if row == 1:
                ax.set_xlabel("time, s")
    return fig


def learners_against_camera(curve: Any, ceiling_of: Any, learners: Sequence[str], names: Mapping[str, str]) -> Figure:
    """Accuracy (%) of each learner against the camera's error (mm, symmetric log scale), air on and off, with
    the exact ceiling dashed and chance dotted. ``curve(learner, air)`` gives (k,) errors in mm and k intervals
    (``study.chapters.motion.Motion.curve``); ``ceiling_of(air)`` the ceiling, a fraction."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8), sharey=True)
    for ax, air in zip(axes, (True, False)):
        for name in learners:
            mm, ivs = curve(name, air)
            ax.errorbar(mm, [100 * iv.value for iv in ivs], capsize=3, marker="o", ms=4,
                        yerr=[[100 * (iv.value - iv.lo) for iv in ivs], [100 * (iv.hi - iv.value) for iv in ivs]],
                        label=names[name])
        ax.axhline(100 * ceiling_of(air), color="black", ls="--", lw=1, label="ceiling")
        ax.axhline(50, color="0.5", ls=":", lw=1)
        ax.set(xscale="symlog", xlabel="camera error, mm (symmetric log scale)", title="air on" if air else "air off")
        ax.set_xlim(left=-0.5)  # errors are never negative: no mirrored decades left of 0
    axes[0].set_ylabel("test accuracy (%)")
    axes[1].legend(fontsize=7, loc="lower left")
    return fig


def engine_agreement(differences: Mapping[str, Any], y: Any, labels: Mapping[str, str]) -> Figure:
    """Histograms, by class, of each per-throw difference Bullet minus MuJoCo. ``differences``: key -> (n,)
    values in the unit its label names; ``y``: (n,) class indices (0 light, 1 heavy); ``labels``: key -> axis
    label."""
    import matplotlib.pyplot as plt
    import numpy as np

    from study import CLASSES

    fig, axes = plt.subplots(1, len(labels), figsize=(12, 3.0), squeeze=False)
    for ax, (k, label) in zip(axes[0], labels.items()):
        d = np.asarray(differences[k])
        lo, hi = np.percentile(d, [1, 99])
        for c, name in enumerate(CLASSES):
            ax.hist(d[y == c], bins=np.linspace(lo, hi + 1e-9, 30), alpha=0.6, label=name, color=CLASS_COLORS[name])
        ax.set(xlabel=f"Bullet − MuJoCo: {label}")
    axes[0, 0].set_ylabel("test throws")
    axes[0, 0].legend()
    return fig
