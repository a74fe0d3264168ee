"""Where a paper build's time went: its wall time, each chapter's, the runs' training CPU by chapter, the renders'
CPU, and the least wall time that much work can take on the build's cores.

Reads a build's ``_build/executed/timings.json`` (written by ``study book``) and the data folder it built in (the
renders keep their times beside the clips, ``RENDER_SECONDS.json``, so a cached render still says what it cost)::

    .venv/bin/python scripts/build_time.py _build/executed/timings.json --data-dir ~/study-cold3 --cores 2

A build resumed across several processes sums its parts' wall times here (``chapters`` and ``stages`` hold the last
process's only: for a build that ran in one go, ``wall_seconds`` is the whole).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def render_cpu(data_dir: Path) -> dict[str, float]:
    """Folder (relative to ``data_dir``) -> CPU seconds its clips took to render, from every ``RENDER_SECONDS.json``."""
    out = {}
    for f in sorted(data_dir.rglob("RENDER_SECONDS.json")):
        try:
            times = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        out[str(f.parent.relative_to(data_dir))] = sum(float(v.get("cpu_s", 0.0)) for v in times.values())
    return out


def report(timings: dict, renders: dict[str, float], cores: int) -> list[str]:
    """The lines :func:`main` prints."""
    lines = [f"wall {timings['wall_seconds'] / 60:.1f} min, the builder's own process {timings['cpu_seconds'] / 60:.1f} "
             f"CPU-min (preset {timings['preset']}, device {timings['device']})"]
    chapters = {k: v for k, v in timings["chapters"].items() if not v.get("cached")}
    lines.append("chapters executed (wall, min; waited for runs): " + ", ".join(
        f"{k} {v['seconds'] / 60:.1f}" + (f" (+{v['waited'] / 60:.1f})" if v.get("waited") else "")
        for k, v in chapters.items()))
    runs = timings["runs"]
    lines.append(f"training: {int(runs['models'])} models, {int(runs['epochs'])} epochs, "
                 f"{runs['cpu_seconds'] / 60:.1f} CPU-min; by chapter: " + ", ".join(
                     f"{k} {v['cpu_seconds'] / 60:.1f}" for k, v in timings["runs_by_chapter"].items()))
    lines.append(f"renders: {sum(renders.values()) / 60:.1f} CPU-min in {len(renders)} folders" + (
        ": " + ", ".join(f"{k} {v / 60:.1f}" for k, v in renders.items()) if renders else ""))
    work = runs["cpu_seconds"] + sum(renders.values())
    lines.append(f"training and renders alone: {work / 60:.1f} CPU-min, at least {work / 60 / cores:.0f} min of wall "
                 f"on {cores} cores")
    failed = timings.get("failed_runs", [])
    reasons: dict[str, int] = {}
    for r in failed:
        reasons[r.get("reason", "?")[:60]] = reasons.get(r.get("reason", "?")[:60], 0) + 1
    lines.append(f"failed runs {len(failed)}: " + "; ".join(f"{n} x {k}" for k, n in reasons.items()))
    lines.append(f"unsettled runs {len(timings.get('unsettled_runs', []))}")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("timings", type=Path, help="the build's _build/executed/timings.json")
    ap.add_argument("--data-dir", type=Path, help="the data folder it built in (for the renders' times)")
    ap.add_argument("--cores", type=int, default=2, help="cores the build had (default 2)")
    a = ap.parse_args(argv)
    try:
        timings = json.loads(a.timings.read_text())
    except (OSError, ValueError) as e:
        print(f"build_time: {a.timings}: cannot read it ({e}); pass a build's _build/executed/timings.json",
              file=sys.stderr)
        return 2
    print("\n".join(report(timings, render_cpu(a.data_dir) if a.data_dir else {}, a.cores)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
