"""Where a paper build's time went: its wall time, each chapter's, the runs' training CPU by chapter, the renders'
CPU (the camera sweep's and the floor path's development clips), and the least wall time that much work needs on
the build's cores when nothing is cached.

Reads a build's ``_build/executed/timings.json`` (written by ``study book``) and, beside it, the build's
``_build/results.json`` for the renders' CPU time (``study.report.usercamera.render_cpu``: the camera sweep's clips
and the floor path's development clips, the build's own, as recorded when they were rendered; a data folder keeps
older builds' clips too)::

    .venv/bin/python scripts/build_time.py _build/executed/timings.json --cores 2

``wall_seconds`` and the chapters' times are the last ``study book`` process's: for a build resumed across several
processes, add up each process's (keep each one's timings.json). The training CPU counts every run the build's
chapters use, cached or not, so the bound holds for a build that trained them all.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections import Counter
from pathlib import Path

from study.book import results
from study.core.errors import DataError
from study.report.usercamera import render_cpu


def sweep_render_cpu(path: Path) -> dict[str, float]:
    """CPU seconds each render took in the build whose results file is ``path``
    (``study.report.usercamera.render_cpu``); ``study.core.errors.DataError`` naming the file if it cannot be read."""
    return render_cpu(results.load(path))


def report(timings: dict, renders: dict[str, float] | None, cores: int) -> list[str]:
    """The lines :func:`main` prints."""
    lines = [f"wall {timings['wall_seconds'] / 60:.1f} min, the builder's own process "
             f"{timings['cpu_seconds'] / 60:.1f} CPU-min (preset {timings['preset']}, device {timings['device']})"]
    chapters = {k: v for k, v in timings["chapters"].items() if not v.get("cached")}
    lines.append("chapters executed (wall, min; + executions that stopped for runs): " + ", ".join(
        f"{k} {v['seconds'] / 60:.1f}" + (f" (+{v['waited'] / 60:.1f})" if v.get("waited") else "")
        for k, v in chapters.items()))
    waits = timings.get("stages", [])
    lines.append(f"waits for runs: {len(waits)}, {sum(s['seconds'] for s in waits) / 60:.1f} min in all")
    runs = timings["runs"]
    lines.append(f"training: {int(runs['models'])} models, {int(runs['epochs'])} epochs, "
                 f"{runs['cpu_seconds'] / 60:.1f} CPU-min; by chapter: " + ", ".join(
                     f"{k} {v['cpu_seconds'] / 60:.1f}" for k, v in timings["runs_by_chapter"].items()))
    work = runs["cpu_seconds"] + sum((renders or {}).values())
    if not renders:
        lines.append("sweep renders: not in the results (no camera sweep, or no results file beside)")
    else:
        lines.append("renders: " + ", ".join(f"{what} {s / 60:.1f} CPU-min" for what, s in renders.items()))
    lines.append(f"training and renders: {work / 60:.1f} CPU-min: a cold build needs at least "
                 f"{math.floor(work / 60 / cores)} min of wall on {cores} cores for them alone")
    failed = timings.get("failed_runs", [])
    reasons = Counter(r.get("reason", "no reason given").split(":")[0] for r in failed)
    lines.append(f"failed runs: {len(failed)}" + "".join(f"\n  {n} x {k}" for k, n in reasons.items()))
    lines.append(f"unsettled runs: {len(timings.get('unsettled_runs', []))}")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("timings", type=Path, help="the build's _build/executed/timings.json")
    ap.add_argument("--results", type=Path, help="the build's results file (default: ../results.json beside it)")
    ap.add_argument("--cores", type=int, default=2, help="cores the build had (default 2)")
    a = ap.parse_args(argv)
    if a.cores < 1:
        print(f"build_time: --cores {a.cores}: give the number of cores the build ran on (1 or more)", file=sys.stderr)
        return 2
    beside = a.results or a.timings.parent.parent / "results.json"
    try:
        renders = sweep_render_cpu(beside) if a.results or beside.is_file() else None
    except DataError as e:
        print(f"build_time: {e}", file=sys.stderr)
        return 2
    try:
        lines = report(json.loads(a.timings.read_text()), renders, a.cores)
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as e:
        print(f"build_time: {a.timings}: cannot read it as a build's timings ({type(e).__name__}: {e}); pass the "
              "_build/executed/timings.json of a 'study book' build", file=sys.stderr)
        return 2
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
