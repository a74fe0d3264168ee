"""Runs per CPU-hour: K training runs trained as one stack (``study.learn.stack``) against the same K trained one at a
time, the whole training loop at Table 1's shape, K = 1, 2, 5, 10, measured in the same run (ratio).

Table 1's shape: 2000 training throws (1600 after the validation part), 3 s at 30 fps (90 frames), Z, two layers
of 64 peephole LSTM units, batch 32, truncation 90 frames; every run a fixed number of epochs (early stopping off,
so every run does the same work). The trajectories are synthetic (a random walk of that shape): the work does not
depend on what they hold. CPU time is the process's own (``getrusage``: user + system), not a run's
``train_seconds``. For each K the K lone runs and the stack of K are timed back to back, twice, the faster of each
kept, so a slow spell of a shared machine hits both.

Needs only NumPy, torch and platformdirs beside the package (``PYTHONPATH=src``), so it runs on a GPU machine's own
Python too: ``--device cuda`` times the stacks there (wall-clock seconds then, synchronised, since the GPU does the
work), and ``--profile`` prints where a step's time goes.

    python benchmarks/bench_stack.py                 # CPU, K = 1, 2, 5, 10
    python benchmarks/bench_stack.py --device cuda --ks 1 10 50 100 --epochs 2
"""

from __future__ import annotations

import argparse
import dataclasses
import resource
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

import numpy as np  # noqa: E402
import torch  # noqa: E402

from study.learn import native, stack, train  # noqa: E402
from study.learn.config import TrainConfig  # noqa: E402
from study.simulate.data import Dataset, Split  # noqa: E402


def cpu_seconds() -> float:
    """This process's CPU time so far, user and system, seconds."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def synthetic(n: int = 2000, frames: int = 90, seed: int = 0) -> Dataset:
    """A data set of Table 1's shape: ``n`` training throws of ``frames`` frames at 30 fps, half of each class."""
    rng = np.random.default_rng(seed)
    x = (1.0 + 0.01 * rng.normal(size=(n, frames, 3)).cumsum(1)).astype(np.float32)
    y = (np.arange(n) % 2).astype(np.int64)
    return Dataset(train=Split(x, y), test=Split(x[:16], y[:16]), fps=30.0, meta={"key": "bench"})


def timed(fn, device: torch.device) -> float:
    """Seconds ``fn()`` costs: process CPU time on the CPU, synchronised wall-clock time on a GPU."""
    if device.type == "cuda":
        torch.cuda.synchronize()
        t0 = time.perf_counter()
        fn()
        torch.cuda.synchronize()
        return time.perf_counter() - t0
    c0 = cpu_seconds()
    fn()
    return cpu_seconds() - c0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ks", type=int, nargs="+", default=[1, 2, 5, 10], help="stack sizes")
    ap.add_argument("--epochs", type=int, default=2, help="epochs of every run")
    ap.add_argument("--device", default="cpu", help="cpu, or cuda")
    ap.add_argument("--profile", action="store_true", help="also print where a step's time goes, K = 1 and the largest")
    ap.add_argument("--alone", type=int, default=None, metavar="N",
                    help="time at most N of the K lone runs (the same work each, so the rate is the same); default: all K")
    a = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    device = torch.device(a.device)
    torch.set_num_threads(1)
    ds = synthetic()
    cfg = TrainConfig(epochs=a.epochs, min_epochs=a.epochs, patience=a.epochs + 1)
    print(f"Table 1's shape: {len(ds.train)} throws, 90 frames, Z, 2 x 64 peephole LSTM, batch 32; {a.epochs} epochs a "
          f"run; device {device}; time loop {native.backend() if device.type == 'cpu' else 'PyTorch (batched)'}")
    train.train_runs([(ds, cfg)], device)  # warm up: the compiled loop, the allocator
    unit = "CPU" if device.type == "cpu" else "GPU wall-clock"
    print(f"{'K':>4}  {'one at a time':>22}  {'one stack':>22}  {'ratio':>6}")
    for K in a.ks:
        cfgs = [dataclasses.replace(cfg, seed=s) for s in range(K)]
        lone = cfgs[: a.alone or K]
        alone = stacked = float("inf")
        for _ in range(2):
            alone = min(alone, timed(lambda: [train.train_runs([(ds, c)], device) for c in lone], device) * K / len(lone))
            stacked = min(stacked, timed(lambda: train.train_runs([(ds, c) for c in cfgs], device), device))
        per_hour = lambda s: 3600 * K / s  # noqa: E731
        print(f"{K:>4}  {per_hour(alone):>12.0f} runs/{unit}-h  {per_hour(stacked):>12.0f} runs/{unit}-h  "
              f"{alone / stacked:>5.2f}x" + (f"  (lone rate from {len(lone)} runs)" if len(lone) < K else ""),
              flush=True)
    if a.profile:
        profile(ds, cfg, device, max(a.ks))
    return 0


def profile(ds: Dataset, cfg: TrainConfig, device: torch.device, K: int) -> None:
    """Where the time of one epoch goes, for a stack of one and a stack of ``K``: the operators by self time."""
    from torch.profiler import ProfilerActivity
    from torch.profiler import profile as torch_profile

    one_epoch = dataclasses.replace(cfg, epochs=1, min_epochs=1)
    for k in sorted({1, K}):
        runs = [(ds, dataclasses.replace(one_epoch, seed=s)) for s in range(k)]
        with torch_profile(activities=[ProfilerActivity.CPU]) as prof:
            train.train_runs(runs, device)
        print(f"\nK = {k}, one epoch:")
        print(prof.key_averages().table(sort_by="self_cpu_time_total", row_limit=12))


if __name__ == "__main__":
    raise SystemExit(main())
