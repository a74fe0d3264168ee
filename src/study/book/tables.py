"""Tidy rows (lists of dicts) as Markdown tables, for chapters that show them with ``IPython.display.Markdown``."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

Format = str | Callable[[Any], str]


def _cell(value: Any, fmt: Format | None) -> str:
    if fmt is None:
        return str(value)
    if callable(fmt):
        return fmt(value)
    return format(value, fmt)


def markdown(rows: Sequence[Mapping[str, Any]], columns: Mapping[str, str], formats: Mapping[str, Format] | None = None) -> str:
    """A Markdown table of ``rows``: ``columns`` maps each field to its header, ``formats`` a field to a
    format spec (``".1%"``) or a function of the value; other fields are shown with ``str``."""
    formats = formats or {}
    lines = ["| " + " | ".join(columns.values()) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        lines.append("| " + " | ".join(_cell(r[c], formats.get(c)) for c in columns) + " |")
    return "\n".join(lines)


def pct(x: float, digits: int = 1) -> str:
    """``0.8123`` -> ``'81.2 %'``."""
    return f"{100 * x:.{digits}f} %"


def pct_pm(mean: float, std: float, digits: int = 1) -> str:
    """Mean and standard deviation of a fraction as ``'81.2 ± 1.3 %'``."""
    return f"{100 * mean:.{digits}f} ± {100 * std:.{digits}f} %"


def pct_ci(interval: Any, digits: int = 1) -> str:
    """An :class:`study.learn.metrics.Interval` of a fraction as ``'81.2 % [79.9, 82.4]'``."""
    return f"{100 * interval.value:.{digits}f} % [{100 * interval.lo:.{digits}f}, {100 * interval.hi:.{digits}f}]"


def runs_note(summary: Mapping[str, Any]) -> str:
    """``''``, or ``'2 of 5 failed to train, 1 diverged, 1 at the epoch cap'`` for a summary row of
    ``study.experiments.summarise``."""
    parts = []
    if summary.get("failed"):
        parts.append(f"{summary['failed']} of {summary['n']} failed to train")
    if summary.get("diverged"):
        parts.append(f"{summary['diverged']} diverged")
    if summary.get("capped"):
        parts.append(f"{summary['capped']} at the epoch cap")
    return ", ".join(parts)


def seeds_ci(correct: Any, digits: int = 1) -> str:
    """A mean over a few seeds as the book shows every one: ``'81.2 % [79.9, 82.4]; t [78.0, 84.1]; 80.1 · 81.5 ·
    82.0'`` -- the bootstrap interval over test throws and seeds, the Student-t interval over the seeds' own
    accuracies, and each seed's. ``correct``: (S, n) bool, seed s got test throw i right."""
    import numpy as np

    from study.learn.metrics import bootstrap_accuracy, t_interval

    c = np.atleast_2d(np.asarray(correct, dtype=bool))
    iv = bootstrap_accuracy(c)
    if len(c) == 1:
        return pct_ci(iv, digits)
    per = c.mean(axis=1)
    t = t_interval(per)
    return (f"{pct_ci(iv, digits)}; t [{100 * t.lo:.{digits}f}, {100 * t.hi:.{digits}f}]; "
            + " · ".join(f"{100 * a:.{digits}f}" for a in per))
