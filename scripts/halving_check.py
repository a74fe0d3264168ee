"""Would successive halving of the grid search pick what the full grid picks? Applies rungs to the per-epoch
validation histories of a build's full-grid run records (``DATA_DIR/runs/*.json``) and prints, per grid and rung,
the points a halved grid would keep and whether the full grid's pick is among them.

With a fixed or plateau schedule a run stopped at epoch R is bitwise the first R epochs of its full run, so its
history's prefix is exactly what a rung would have seen: no retraining is needed. A point's score at a rung is the
paper's pick rule (``study.runs.paper.best_config``) on that prefix: the mean over seeds of the validation accuracy
at each seed's lowest validation loss so far, ties broken by the lower mean loss::

    .venv/bin/python scripts/halving_check.py ~/study-cold --rungs 10 20 30 40 60
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

def _at(history: list[dict[str, float]], rung: int) -> tuple[float, float]:
    """(validation accuracy, loss) at the lowest validation loss within the first ``rung`` epochs."""
    seen = history[:rung]
    best = min(seen, key=lambda e: e["val_loss"])
    return best["val_accuracy"], best["val_loss"]


def grids(data_dir: Path, preset: str = "paper") -> dict[tuple[str, str], dict[tuple[float, int], list[list[dict]]]]:
    """(cell, inputs) -> grid point (lr, truncation) -> each grid seed's history: the records of exactly the runs
    Table 1's chapter trains for its grids (``study.runs.paper.grid_configs``), those that are in ``data_dir``."""
    from study.runs import Runner, paper, records

    runner = Runner.open(preset, 0, data_dir)
    out: dict = defaultdict(lambda: defaultdict(list))
    wanted = [(cell, "positions") for cell in runner.preset.cells] + [("peephole", "velocity")]
    for cell, inputs in wanted:
        for cfg in paper.grid_configs(runner.preset, cell, inputs):
            path = records.record_path(data_dir, records.run_key(runner.dataset, cfg, False, runner.device))
            if path.is_file():
                out[cell, inputs][cfg.lr, cfg.truncation].append(json.loads(path.read_text())["history"])
    return out


def pick(points: dict[tuple[float, int], list[list[dict[str, float]]]], rung: int | None) -> list[tuple[float, int]]:
    """The points in the order the pick rule ranks them at ``rung`` (None: the full histories)."""
    def score(p: tuple[float, int]) -> tuple[float, float]:
        got = [_at(h, rung or len(h)) for h in points[p]]
        return (-sum(a for a, _ in got) / len(got), sum(v for _, v in got) / len(got))
    return sorted(points, key=score)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data_dir", type=Path, help="a build's data folder (its runs/ holds the run records)")
    ap.add_argument("--rungs", type=int, nargs="+", default=[10, 20, 30, 40, 60], help="epochs at which to halve")
    a = ap.parse_args(argv)
    missed = 0
    for (cell, inputs), points in sorted(grids(a.data_dir).items()):
        if len(points) < 2 or len({len(h) for h in points.values()}) > 1:
            print(f"{cell}, {inputs}: not every point has all its seeds in this data folder; skipped")
            continue
        full = pick(points, None)[0]
        print(f"{cell}, {inputs}: the full grid picks lr {full[0]:g}, truncation {full[1]}")
        for rung in a.rungs:
            kept = pick(points, rung)[: max(1, len(points) // 2)]
            ok = full in kept
            missed += not ok
            print(f"  rung {rung:>3}: keeps {', '.join(f'({p[0]:g}, {p[1]})' for p in kept)}"
                  + ("" if ok else "  <- drops the full grid's pick"))
    print(f"{missed} rung(s) drop the full grid's pick")
    return 0


if __name__ == "__main__":
    sys.exit(main())
