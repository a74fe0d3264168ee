"""Would a longer plateau allowance save a build's failures by chance? Each failed run of a data folder's records that
the book does not mean to fail (``study.runs.failures``) is trained again alone with ``plateau_epochs`` raised (the
plateau rule stops a run still on the plateau after ``plateau_epochs``), and the script prints when it left the
plateau (its validation loss below ``PLATEAU_LOSS``), its best epoch and accuracy, and whether its first epochs are
bitwise the recorded run's (a lone run is its stack member's, so they must be)::

    .venv/bin/python scripts/plateau_allowance.py ~/study-cold --plateau-epochs 120 [--most 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    from study.learn import train
    from study.learn.config import TrainConfig
    from study.learn.metrics import PLATEAU_LOSS
    from study.runs import Runner, failures
    from study.simulate import synth

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data_dir", type=Path, help="a build's data folder (runs/ holds its run records)")
    ap.add_argument("--plateau-epochs", type=int, default=120, help="the raised allowance (default 120)")
    ap.add_argument("--most", type=int, default=0, help="retrain at most this many (0: all)")
    a = ap.parse_args(argv)
    records = [json.loads(f.read_text()) for f in sorted((a.data_dir / "runs").glob("*.json"))]
    chance = [r for r in records if r.get("failed") and failures.reason(r["config"], r.get("fps")) == failures.BY_CHANCE]
    print(f"{len(chance)} of {len(records)} runs failed by chance")
    runner = Runner.open("paper", 0, a.data_dir)
    datasets = {}
    for r in chance[: a.most or None]:
        cfg = dataclasses.replace(TrainConfig(**r["config"]), plateau_epochs=a.plateau_epochs)
        if r["data_key"] not in datasets:
            path = next(a.data_dir.glob(f"*-{r['data_key']}.npz"), None)
            datasets[r["data_key"]] = synth.load(path) if path else runner.dataset
        tm = train.fit(datasets[r["data_key"]], cfg, progress=False, warn=False)
        left = next((e["epoch"] for e in tm.history if e["val_loss"] < PLATEAU_LOSS), None)
        same = all(x["val_loss"] == y["val_loss"] for x, y in zip(tm.history, r["history"]))
        c = r["config"]
        print(f"{c['cell']} {c['inputs']} {c['dims']} {c['length']:g} s, truncation {c['truncation']}, seed {c['seed']}: "
              f"left the plateau at epoch {left}, best {tm.best_epoch} of {len(tm.history)}, "
              f"{100 * tm.val_accuracy:.1f} %, {tm.training_state}; first {len(r['history'])} epochs "
              + ("bitwise the record's" if same else "NOT the record's"), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
