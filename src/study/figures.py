"""One matplotlib style for the whole book: colour-blind-safe colours, units on axes, stable files.

Chapters call :func:`use_style` once, colour the two classes with :data:`CLASS_COLORS`, and write
figure files with :func:`save`, which gives the same bytes for the same figure (no dates, no random
SVG ids), so a re-run that changed nothing changes no file. Nothing here selects a GUI backend: it
works under Agg (scripts, tests) and under the notebook's inline backend alike.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib as mpl
from matplotlib.figure import Figure

from study.cache import atomic_path
from study.errors import ConfigError

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

_FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}
# Metadata keys that would otherwise carry the date or the library version into the file.
_METADATA: dict[str, dict[str, Any]] = {
    "png": {"Software": None},
    "svg": {"Date": None, "Creator": None},
    "pdf": {"CreationDate": None, "ModDate": None, "Producer": None, "Creator": None},
}


def use_style() -> None:
    """Apply :data:`STYLE` to matplotlib's global rcParams (call once at the top of a chapter)."""
    mpl.rcParams.update(STYLE)


def save(fig: Figure, path: str | Path, dpi: float | None = None) -> Path:
    """Write ``fig`` to ``path`` (.png, .svg or .pdf) atomically, with no date or version inside.

    The same figure drawn by the same library versions gives the same bytes. ``dpi`` defaults to the
    style's ``savefig.dpi`` (150). Returns ``path`` as a :class:`Path`.
    """
    target = Path(path)
    fmt = _FORMATS.get(target.suffix.lower())
    if fmt is None:
        raise ConfigError(f"figure file {target}: unknown suffix {target.suffix!r}; use one of {sorted(_FORMATS)}")
    with mpl.rc_context({"svg.hashsalt": STYLE["svg.hashsalt"], "svg.fonttype": STYLE["svg.fonttype"]}):
        with atomic_path(target) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi or STYLE["savefig.dpi"], metadata=_METADATA[fmt])
    return target
