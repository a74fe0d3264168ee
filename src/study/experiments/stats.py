"""Summaries of runs: a mean, a spread and a 95 % interval per group of rows, and the questions the chapters ask
of them.

Rows are the tidy dicts of ``study.experiments.runs.row`` (one per run); a row scored on the test split carries
``correct``, (n,) bool, which test trajectories it got right, so intervals can resample both the test
trajectories and the seeds.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from study.learn.metrics import Interval, bootstrap_accuracy


def summarise(rows: list[dict], by: tuple[str, ...], value: str = "accuracy") -> list[dict]:
    """Group ``rows`` by the ``by`` fields: n, mean, sample std (ddof=1; 0 for one run), min and best of
    ``value``; the runs that failed to train, diverged, or stopped at the epoch cap; and, where rows carry
    ``correct``, ``interval``: the 95 % bootstrap interval of the mean over test trajectories and seeds."""
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault(tuple(r[b] for b in by), []).append(r)
    out = []
    for k, g in groups.items():
        a = np.asarray([float(r[value]) for r in g])
        s = {**dict(zip(by, k)), "n": len(a), "mean": float(a.mean()),
             "std": float(a.std(ddof=1)) if len(a) > 1 else 0.0, "min": float(a.min()), "best": float(a.max()),
             "failed": sum(bool(r.get("failed")) for r in g),
             "diverged": sum(r.get("diverged_epoch") is not None for r in g),
             "capped": sum(bool(r.get("capped")) for r in g)}
        if value == "accuracy" and all("correct" in r for r in g):
            s["interval"] = bootstrap_accuracy(np.stack([r["correct"] for r in g]))
        out.append(s)
    return out


def mean_interval(rows: list[dict], **where: Any) -> Interval:
    """The interval of :func:`summarise` for the rows whose fields equal ``where`` (all rows if none)."""
    picked = [r for r in rows if all(r[k] == v for k, v in where.items())]
    return summarise(picked, ())[0]["interval"]


def best_run_interval(rows: list[dict]) -> tuple[dict, Interval]:
    """The row with the highest test accuracy and the bootstrap interval of that one run (the paper's
    number is a best run: compare it with ours)."""
    best = max(rows, key=lambda r: r["accuracy"])
    return best, bootstrap_accuracy(best["correct"])


def scored(models: Sequence[Any], x: np.ndarray, y: np.ndarray) -> Interval:
    """The mean accuracy of ``models`` on trajectories ``x`` (n, T, 3) with labels ``y``, and its bootstrap
    interval over the trajectories and the models (seeds)."""
    correct = np.stack([m.predict_proba(x).argmax(axis=1) == np.asarray(y) for m in models])
    return bootstrap_accuracy(correct)


def long_input_effect(summary: list[dict], dims: str) -> dict[str, Any]:
    """Does accuracy fall at the longest inputs? From :func:`summarise` rows grouped by (dims, length).

    Compares the best mean accuracy over lengths with the mean at the longest length; ``hurts`` when
    their 95 % intervals do not overlap and the longest is below.
    """
    rows = sorted((r for r in summary if r["dims"] == dims), key=lambda r: r["length"])
    best = max(rows, key=lambda r: r["mean"])
    last = rows[-1]
    drop = best["mean"] - last["mean"]
    hurts = best is not last and drop > 0 and not best["interval"].overlaps(last["interval"])
    return {"dims": dims, "best_length": best["length"], "best_mean": best["mean"], "last_length": last["length"],
            "last_mean": last["mean"], "drop": drop, "hurts": bool(hurts)}


def intervals_agree(intervals: Sequence[Interval]) -> bool:
    """Whether every pair of ``intervals`` overlaps: the seeds of a number agree, none differs significantly from
    another. False when the seeds split into groups (some trained, some stalled): the pooled mean of such seeds
    is not yet a number."""
    return all(a.overlaps(b) for i, a in enumerate(intervals) for b in intervals[i + 1:])


def mean_difference(a: np.ndarray, b: np.ndarray, n_boot: int = 2000, seed: int = 0) -> Interval:
    """The mean of ``a`` (n,) minus the mean of ``b`` (m,), two independent samples, with a percentile bootstrap
    interval (each resampled within itself), 95 %."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    rng = np.random.default_rng(seed)
    stats = rng.choice(a, (n_boot, len(a))).mean(1) - rng.choice(b, (n_boot, len(b))).mean(1)
    lo, hi = np.quantile(stats, [0.025, 0.975])
    return Interval(float(a.mean() - b.mean()), float(lo), float(hi),
                    f"bootstrap of the difference of two means ({len(a)} and {len(b)} throws)")


def bootstrap_mean(values: np.ndarray, n_boot: int = 2000, seed: int = 0) -> Interval:
    """The mean of ``values`` (n,) with a percentile bootstrap interval over them, 95 %."""
    v = np.asarray(values, float)
    rng = np.random.default_rng(seed)
    lo, hi = np.quantile(rng.choice(v, (n_boot, len(v))).mean(1), [0.025, 0.975])
    return Interval(float(v.mean()), float(lo), float(hi), f"bootstrap over {len(v)} values")
