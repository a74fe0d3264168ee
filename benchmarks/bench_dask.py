"""Throughput of a batch of training runs on the local process pool against a Dask LocalCluster, in one run.

The same batch of smoke-preset runs (Table 1's smoke configuration over many seeds, Z and X, Y, Z) is trained
twice into fresh data folders: by ``study.runs.schedule.run_all`` on a pool of spawned processes (the
default), and on a ``LocalCluster`` with one single-threaded worker per core (``study book --scheduler local``).
Prints runs per minute for each, the cluster's throughput over the pool's (1.0 = as fast), and whether the
two gave the same records (they must). The cluster's start-up is timed apart.

    python benchmarks/bench_dask.py [--runs 16] [--workers N]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import tempfile
import time
from pathlib import Path

from study.runs import cluster, paper, preset, schedule
from study.simulate import synth


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=16, help="runs in the batch (default: %(default)s)")
    ap.add_argument("--workers", type=int, default=0, help="processes / Dask workers (0: one per CPU)")
    ap.add_argument("--epochs", type=int, default=10, help="epochs per run (the smoke preset's 3 are mostly start-up)")
    a = ap.parse_args(argv)
    workers = a.workers or cluster.default_workers()
    p = preset("smoke")
    with tempfile.TemporaryDirectory() as tmp:
        ds = synth.dataset("smoke", seed=0, data_dir=Path(tmp) / "data", progress=False)
        base = dataclasses.replace(p.base_config(), epochs=a.epochs, min_epochs=a.epochs)
        cfgs = paper.seed_configs(base, tuple(range(a.runs // 2)))
        t0 = time.perf_counter()
        local = schedule.run_all(ds, cfgs, Path(tmp) / "pool", True, workers=workers)
        t_pool = time.perf_counter() - t0
        t0 = time.perf_counter()
        schedule.client("local", workers)
        t_start = time.perf_counter() - t0
        t0 = time.perf_counter()
        dask = schedule.run_all(ds, cfgs, Path(tmp) / "dask", True, workers=workers, scheduler="local")
        t_dask = time.perf_counter() - t0
        same = all({k: v for k, v in x.items() if k != "train_seconds"} == {k: v for k, v in y.items() if k != "train_seconds"}
                   for x, y in zip(local, dask))
        records = sorted(f.name for f in (Path(tmp) / "dask" / "runs").glob("*.json"))
        assert records == sorted(f.name for f in (Path(tmp) / "pool" / "runs").glob("*.json"))
        cpu = sum(json.loads((Path(tmp) / "pool" / "runs" / n).read_text())["train_seconds"] for n in records)
    n = len(cfgs)
    print(f"{n} smoke runs on {workers} workers ({cpu:.1f} s of training in the records)")
    print(f"local process pool: {t_pool:6.1f} s  {60 * n / t_pool:6.1f} runs/min (pool start-up included)")
    print(f"Dask LocalCluster : {t_dask:6.1f} s  {60 * n / t_dask:6.1f} runs/min (cluster start-up {t_start:.1f} s apart)")
    print(f"ratio, cluster / pool throughput: {t_pool / t_dask:.2f} (the cluster's start-up apart), "
          f"{t_pool / (t_dask + t_start):.2f} (with it); identical records: {same}")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
