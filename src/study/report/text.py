"""Numbers, intervals and tables as the book writes them: ``81.2 % [79.9, 82.4]``, ``+1.2 points [-0.3, +2.6]``,
and tidy rows (lists of dicts) as Markdown tables, which the chapters' results render and the book shows."""

from __future__ import annotations

import csv
import io
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from study.core import cache
from study.learn.metrics import bootstrap_accuracy, t_interval

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


@dataclass(frozen=True)
class Table:
    """A table a chapter's result renders: tidy rows, the fields shown with their headers, and their formats."""

    rows: Sequence[Mapping[str, Any]]
    """One mapping per row."""
    columns: Mapping[str, str]
    """Field -> header, in the order shown."""
    formats: Mapping[str, Format] = field(default_factory=dict)
    """Field -> a format spec (``".1%"``) or a function of the value; other fields are shown with ``str``."""
    empty: str = ""
    """Markdown shown instead when there are no rows (``""``: the header alone)."""

    def markdown(self) -> str:
        """The table in Markdown (:attr:`empty` if it has no rows and that is set)."""
        if not self.rows and self.empty:
            return self.empty
        return markdown(self.rows, self.columns, self.formats)

    def write_csv(self, path: str | Path) -> Path:
        """The rows as a CSV file at ``path`` (written atomically; one column per shown field, its name as the
        header, raw values): what a reader takes into their own analysis. Raises ``OutputError`` naming ``path``
        if it cannot be written."""
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=list(self.columns), extrasaction="ignore", lineterminator="\n")
        w.writeheader()
        w.writerows(self.rows)
        cache.write_text_atomic(path, buf.getvalue())
        return Path(path)


@dataclass(frozen=True)
class Bullets:
    """A list a chapter's result renders: one Markdown bullet per item."""

    items: Sequence[str]
    """The items, in order (Markdown)."""

    def markdown(self) -> str:
        """The list in Markdown."""
        return "\n".join(f"- {item}" for item in self.items)


def pct(x: float, digits: int = 1) -> str:
    """``0.8123`` -> ``'81.2 %'``."""
    return f"{100 * x:.{digits}f} %"


def pct_pm(mean: float, std: float, digits: int = 1) -> str:
    """Mean and standard deviation of a fraction as ``'81.2 ± 1.3 %'``."""
    return f"{100 * mean:.{digits}f} ± {100 * std:.{digits}f} %"


def pct_ci(interval: Any, digits: int = 1) -> str:
    """An :class:`study.learn.metrics.Interval` of a fraction as ``'81.2 % [79.9, 82.4]'``."""
    return f"{100 * interval.value:.{digits}f} % [{100 * interval.lo:.{digits}f}, {100 * interval.hi:.{digits}f}]"


def runs_note(summary: Any) -> str:
    """``''``, or ``'2 of 5 failed to train, 1 diverged, 1 at the epoch cap'`` for a
    ``study.runs.stats.Summary``."""
    parts = []
    if summary.failed:
        parts.append(f"{summary.failed} of {summary.n} failed to train")
    if summary.diverged:
        parts.append(f"{summary.diverged} diverged")
    if summary.capped:
        parts.append(f"{summary.capped} at the epoch cap")
    return ", ".join(parts)


def points(interval: Any, digits: int = 1) -> str:
    """A difference of fractions in points with its interval: ``'+1.2 points [-0.3, +2.6]'``."""
    return (f"{100 * interval.value:+.{digits}f} points [{100 * interval.lo:+.{digits}f}, "
            f"{100 * interval.hi:+.{digits}f}]")


def _scale(unit: str) -> tuple[float, str, str]:
    """Factor, suffix and format spec of a unit: percentages to a tenth of a point, as in the chapters."""
    if unit == "fraction":
        return 100.0, " %", ".1f"
    return 1.0, "" if unit == "count" else f" {unit}", ".3g"


def fmt_value(value: float, unit: str = "fraction") -> str:
    """``'81.2 %'`` for a fraction, ``'12'`` for a count, ``'0.41 s'`` otherwise."""
    scale, suffix, spec = _scale(unit)
    return f"{scale * value:{spec}}{suffix}"


def fmt(leaf: Any) -> str:
    """A reported number with its interval, ``'81.2 % [79.9, 82.4]'`` (no interval for an exact number; a
    difference with its sign, in points for fractions); a verdict, its word."""
    if not hasattr(leaf, "value"):  # a study.report.reported.Verdict
        return leaf.verdict
    if leaf.lo == leaf.hi == leaf.value:
        return fmt_value(leaf.value, leaf.unit)
    if getattr(leaf, "signed", False):
        if leaf.unit == "fraction":
            return points(leaf)
        _, suffix, spec = _scale(leaf.unit)
        return f"{leaf.value:+{spec}}{suffix} [{leaf.lo:+{spec}}, {leaf.hi:+{spec}}]"
    scale, _, spec = _scale(leaf.unit)
    return f"{fmt_value(leaf.value, leaf.unit)} [{scale * leaf.lo:{spec}}, {scale * leaf.hi:{spec}}]"


def seeds_ci(correct: Any, digits: int = 1) -> str:
    """A mean over a few seeds as the book shows every one: ``'81.2 % [79.9, 82.4]; t [78.0, 84.1]; 80.1 · 81.5 ·
    82.0'`` -- the bootstrap interval over test throws and seeds, the Student-t interval over the seeds' own
    accuracies, and each seed's. ``correct``: (S, n) bool, seed s got test throw i right."""
    c = np.atleast_2d(np.asarray(correct, dtype=bool))
    iv = bootstrap_accuracy(c)
    if len(c) == 1:
        return pct_ci(iv, digits)
    per = c.mean(axis=1)
    t = t_interval(per)
    return (f"{pct_ci(iv, digits)}; t [{100 * t.lo:.{digits}f}, {100 * t.hi:.{digits}f}]; "
            + " · ".join(f"{100 * a:.{digits}f}" for a in per))
