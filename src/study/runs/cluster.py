"""Where runs are trained, without torch (so the book's builder and the command line can import it cheaply): how
many local processes, a Dask ``LocalCluster`` set up the one way the study starts one, and the file a chapter
lists its runs in for the builder to count them.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any


def device(name: str = "auto") -> str:
    """The torch device ``name`` names: ``"auto"`` is ``"cuda"`` where a GPU is at hand, else ``"cpu"``."""
    if name != "auto":
        return name
    import torch  # imported here: the command line's help must not load torch

    return "cuda" if torch.cuda.is_available() else "cpu"


def default_workers() -> int:
    """Training processes to run at once: the CPUs this process may use (each run takes one thread)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def local_cluster(workers: int) -> Any:
    """A Dask ``LocalCluster`` of ``workers`` single-threaded worker processes, listening on the loopback address
    only (a Dask scheduler runs whatever code reaches it), without a dashboard."""
    from distributed import (
        LocalCluster,  # Dask is imported only where a cluster is asked for
    )

    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                        dashboard_address=None)


def _entries(parts: Sequence[Path]) -> list[tuple[Path, dict[str, Any]]]:
    """Every line of the plan files ``parts`` that reads as a JSON object, with the part it is in (a missing file
    has none)."""
    out = []
    for part in parts:
        if not part.is_file():
            continue
        for line in part.read_text().splitlines():
            with contextlib.suppress(ValueError):
                entry = json.loads(line)
                if isinstance(entry, dict):
                    out.append((part, entry))
    return out


def _planned(entries: Sequence[tuple[Path, dict[str, Any]]]) -> dict[str, tuple[str, Path]]:
    """Each distinct model of a plan's ``entries`` (:func:`_entries`): its record's path and the first part that
    lists it (a line without a record, ``schedule.Plan.reject``'s, adds none)."""
    models: dict[str, tuple[str, Path]] = {}
    for part, entry in entries:
        if "model" in entry and "record" in entry:
            models.setdefault(str(entry["model"]), (str(entry["record"]), part))
    return models


def _rejected(entries: Sequence[tuple[Path, dict[str, Any]]]) -> frozenset[str]:
    """The models a plan's ``entries`` say a chapter trained as candidates and did not choose
    (``schedule.Plan.reject``)."""
    return frozenset(str(e["model"]) for _, e in entries if e.get("rejected") and "model" in e)


def _totals(records: Sequence[str]) -> dict[str, float]:
    seconds = epochs = failed = 0.0
    for record in records:
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            rec = json.loads(Path(record).read_text())
            seconds += float(rec.get("cpu_seconds", rec["train_seconds"]))
            epochs += float(rec.get("epochs_run", 0))
            failed += bool(rec.get("failed"))
    return {"models": float(len(records)), "cpu_seconds": seconds, "epochs": epochs, "failed": failed}


def plan_totals(parts: Sequence[Path]) -> dict[str, float]:
    """The distinct models listed in the plan files ``parts`` (``models``), the process CPU seconds their records
    took to train (``cpu_seconds``: each record's ``cpu_seconds``, or its wall ``train_seconds`` if it was made
    before that was kept), the epochs they ran (``epochs``) and how many failed to train (``failed``); a record
    that is missing counts nothing but its model."""
    return _totals([record for record, _ in _planned(_entries(parts)).values()])


def plan_listed(parts: Sequence[Path]) -> dict[str, list[dict[str, Any]]]:
    """The failed runs and the runs still improving at their budget of the plan files ``parts``, in one pass over
    their records (``study.runs.failures.listed``)."""
    from study.runs.failures import listed

    entries = _entries(parts)  # each plan file read once
    return listed(_planned(entries), _rejected(entries))


def plan_by_part(parts: Sequence[Path]) -> dict[str, dict[str, float]]:
    """:func:`plan_totals` of each plan file (by its name without suffix: the chapter), each model counted in the
    first part that lists it, so the parts add up to the whole: where a build's training time goes."""
    by: dict[Path, list[str]] = {p: [] for p in parts}
    for record, part in _planned(_entries(parts)).values():
        by[part].append(record)
    return {p.stem: _totals(records) for p, records in by.items() if records}
