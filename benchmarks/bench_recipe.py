"""Which training recipe settles? Candidate recipes on the networks whose validation swings most, chosen on
validation data only, then confirmed; the test accuracy is printed after the choice.

For each candidate recipe (:data:`CANDIDATES`: the constant rate with early stopping the study used before, the rate halved on
plateaus, fixed cosine budgets with a warm-up, an exponential moving average of the weights, a larger batch at a
scaled rate) and each screened network (:data:`SCREEN`: speed X, Y, Z and velocity Z, at the command line's
defaults otherwise), over ``--seeds`` seeds on one data set (the preset's, data seed 0), it prints:

- the validation accuracy of the kept weights (mean and range over seeds);
- how much the validation accuracy still moves over the last 10 epochs run (max - min, mean over seeds): a recipe
  *settles* when this is at most :data:`SETTLED` points on every screened network;
- epochs run (mean) and process CPU seconds per run (the training processes' own time, not wall time);
- each against that recipe (:data:`BASELINE`), measured in the same run (ratios).

With ``--confirm``, every recipe that settles and the baseline are then trained on the other networks
(:data:`CONFIRM`: positions Z, Table 1's; positions X, Y, Z; the every-frame Z network of the decision chapter)
with ``--confirm-seeds`` seeds. The choice (:func:`choose`): of the recipes that settle, those as good as the best
(within :data:`NEAR` points of its mean validation accuracy, or a paired difference over seeds whose 95 % interval
holds 0), the one with the fewest epochs a run over every network measured. Only then are the test accuracies
printed (mean and range over seeds). Every run is cached in ``--data-dir`` like the book's (``study.runs.records``), so a
second invocation prints at once.

    python benchmarks/bench_recipe.py                         # smoke: a minute, nothing to conclude from
    python benchmarks/bench_recipe.py --preset paper --seeds 5 --confirm    # the real question (hours on 2 cores)
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from study.learn.config import TrainConfig
from study.runs.failures import CLIMB, LAST, SETTLED, swing_and_climb  # the build's settle rule, the same numbers
from study.runs import schedule
from study.simulate import synth

RAW = {"average": "none"}
"""The optimiser's own weights validated and kept (the study's recipe before it averaged them)."""
CANDIDATES: dict[str, dict[str, Any]] = {
    "constant (before)": dict(RAW),
    "plateau": {"lr_schedule": "plateau", **RAW},
    "constant + EMA": {"average": "ema"},
    "cosine 60, 3e-3, warm-up 3": {"lr_schedule": "cosine", "epochs": 60, "lr": 3e-3, "warmup_epochs": 3, **RAW},
    "cosine 60, 3e-3, warm-up 3, EMA": {"lr_schedule": "cosine", "epochs": 60, "lr": 3e-3, "warmup_epochs": 3,
                                        "average": "ema"},
    "cosine 100, 1e-3": {"lr_schedule": "cosine", "epochs": 100, **RAW},
    "cosine 100, 1e-3, EMA": {"lr_schedule": "cosine", "epochs": 100, "average": "ema"},
    "constant + EMA 0.995": {"average": "ema", "ema_decay": 0.995},
    "cosine 150, 1e-3": {"lr_schedule": "cosine", "epochs": 150, **RAW},
    "batch 128, 4e-3, cosine 60, warm-up 3": {"lr_schedule": "cosine", "epochs": 60, "lr": 4e-3,
                                              "warmup_epochs": 3, "batch_size": 128, **RAW},
}
"""Recipe name -> the TrainConfig fields it sets (the rest: TrainConfig's defaults, patience 20 and so on)."""
BASELINE = "constant (before)"
"""The recipe the others are measured against."""
SCREEN: dict[str, dict[str, Any]] = {"speed X, Y, Z": {"dims": "xyz", "inputs": "speed"},
                                     "velocity Z": {"dims": "z", "inputs": "velocity"}}
"""The networks whose validation loss swings most with a constant rate (issue 'Numbers that hold still')."""
CONFIRM: dict[str, dict[str, Any]] = {"positions Z": {"dims": "z"}, "positions X, Y, Z": {"dims": "xyz"},
                                      "every frame, velocity Z": {"dims": "z", "inputs": "velocity", "loss_at": "every"}}
"""The networks the choice is confirmed on (the decision chapter's answers at every frame)."""
NEAR = 0.5
"""Points: recipes this close to the best settled validation accuracy count as equally good; the cheapest wins."""
SMOKE_EPOCHS = 4
"""On the smoke preset every budget is cut to this (the smoke data set cannot tell recipes apart)."""


@dataclass(frozen=True)
class Row:
    """One recipe on one network, over the seeds."""

    recipe: str
    network: str
    val: list[float]
    """Validation accuracy of the kept weights, per seed."""
    swing: list[float]
    """Max - min validation accuracy over the last :data:`LAST` epochs run, per seed."""
    climb: list[float]
    """Mean validation accuracy of the last :data:`LAST` epochs minus that of the :data:`LAST` before, per seed."""
    epochs: list[int]
    test: list[float]
    failed: int
    cpu: float
    """Process CPU seconds per run (its record's, ``cpu_seconds``)."""


def config(recipe: dict[str, Any], network: dict[str, Any], seed: int, smoke: bool) -> TrainConfig:
    """Today's defaults with the network's and the recipe's changes (budgets cut on the smoke preset)."""
    cfg = dataclasses.replace(TrainConfig(), seed=seed, **network, **recipe)
    if smoke:
        warm = min(cfg.warmup_epochs, 1)
        cfg = dataclasses.replace(cfg, length=1.0, truncation=10, epochs=SMOKE_EPOCHS, min_epochs=2, patience=2,
                                  warmup_epochs=warm)
    cfg.check()
    return cfg


def plan(recipes: Sequence[str], networks: dict[str, dict[str, Any]], seeds: Sequence[int],
         smoke: bool) -> dict[tuple[str, str], list[TrainConfig]]:
    """(recipe, network) -> its configs, one per seed."""
    return {(name, net): [config(CANDIDATES[name], changes, s, smoke) for s in seeds]
            for name in recipes for net, changes in networks.items()}


def measure(ds, cfgs: dict[tuple[str, str], list[TrainConfig]], data_dir: Path, workers: int | None) -> list[Row]:
    """Train (or read) every run of ``cfgs`` at once (every core busy to the end), then one row per
    (recipe, network): validation, settling, epochs, process CPU seconds per run (the records' own)."""
    jobs = [(ds, c, True) for group in cfgs.values() for c in group]
    recs = iter(schedule.run_many(jobs, data_dir, desc="recipes", progress=True, workers=workers))
    rows = []
    for (recipe, network), group in cfgs.items():
        rs = [next(recs) for _ in group]
        swing, climb = [], []
        for r in rs:
            acc = [h["val_accuracy"] for h in r["history"] if np.isfinite(h["val_accuracy"])]
            sc = swing_and_climb(acc) if acc else (float("nan"), 0.0)
            swing.append(sc[0])
            climb.append(sc[1])
        cpu = float(np.mean([r.get("cpu_seconds", r["train_seconds"]) for r in rs]))
        rows.append(Row(recipe, network, [100 * r["val_accuracy"] for r in rs], swing, climb,
                        [r["epochs_run"] for r in rs],
                        [100 * r["test"]["accuracy"] for r in rs], sum(bool(r["failed"]) for r in rs), cpu))
    return rows


def settled_recipes(rows: Sequence[Row]) -> tuple[list[str], dict[str, str]]:
    """The recipes that settle on every network of ``rows`` (and train on every seed), and why each other does
    not."""
    recipes = list(dict.fromkeys(r.recipe for r in rows))
    of = {name: [r for r in rows if r.recipe == name] for name in recipes}
    settled = [n for n in recipes if all(np.mean(r.swing) <= SETTLED and np.mean(r.climb) <= CLIMB and not r.failed
                                         for r in of[n])]
    why = {n: "does not settle" if any(np.mean(r.swing) > SETTLED or r.failed for r in of[n])
           else "still climbing" for n in recipes if n not in settled}
    return settled, why


def paired_gap(rows: Sequence[Row], a: str, b: str) -> tuple[float, float, float]:
    """Validation points by which recipe ``b`` trails ``a``, paired by network and seed: the mean and its 95 %
    t-interval (lo, hi)."""
    of = {(r.recipe, r.network): r for r in rows}
    gaps = [va - vb for net in dict.fromkeys(r.network for r in rows) if (a, net) in of and (b, net) in of
            for va, vb in zip(of[a, net].val, of[b, net].val)]
    m = float(np.mean(gaps))
    half = float(stats.t.ppf(0.975, len(gaps) - 1) * np.std(gaps, ddof=1) / np.sqrt(len(gaps))) if len(gaps) > 1 else 0.0
    return m, m - half, m + half


def choose(rows: Sequence[Row], cost_rows: Sequence[Row] = ()) -> tuple[str, dict[str, str]]:
    """The chosen recipe on validation data alone (see the module's docstring), and why each other was not.

    Of the recipes that settle on the screened networks (``rows``), those as good as the best: within
    :data:`NEAR` points of its mean validation accuracy, or trailing it by a paired difference whose 95 % interval
    holds 0 (the seeds cannot tell them apart). Of those, the one with the fewest epochs per run, counted over
    ``rows`` and, where given, ``cost_rows`` (the confirmation's networks: on the screened ones every
    averaging recipe runs its whole budget, so only the others tell what a recipe costs the whole study)."""
    settled, why = settled_recipes(rows)
    failing = {r.recipe for r in cost_rows if r.failed}  # a seed that did not train on the other networks
    why |= {n: "a seed failed to train on the confirmation's networks" for n in settled if n in failing}
    settled = [n for n in settled if n not in failing]
    if not settled:
        return BASELINE, why | {BASELINE: "none settles: the baseline stays"}
    of = {name: [r for r in [*rows, *cost_rows] if r.recipe == name] for name in settled}
    val = {n: float(np.mean([np.mean(r.val) for r in rows if r.recipe == n])) for n in settled}
    best = max(val, key=lambda n: val[n])
    gap = {n: paired_gap(rows, best, n) for n in settled}
    near = [n for n in settled if val[n] >= val[best] - NEAR or gap[n][1] <= 0]
    epochs = {n: float(np.mean([e for r in of[n] for e in r.epochs])) for n in near}
    chosen = min(near, key=lambda n: (epochs[n], -val[n]))
    why |= {n: f"settles, {gap[n][0]:.1f} points below the best [{gap[n][1]:.1f}, {gap[n][2]:.1f}]"
            for n in settled if n not in near}
    why |= {n: ("the best on validation" if n == best else
                f"as good ({gap[n][0]:.1f} points [{gap[n][1]:.1f}, {gap[n][2]:.1f}] from the best)")
               + f", {epochs[n]:.0f} epochs a run against {epochs[chosen]:.0f}" for n in near if n != chosen}
    return chosen, why


def _pm(values: Sequence[float]) -> str:
    return f"{np.mean(values):5.1f} [{min(values):.1f}, {max(values):.1f}]"


def print_validation(rows: Sequence[Row]) -> None:
    base = {r.network: r for r in rows if r.recipe == BASELINE}
    print(f"\n{'recipe':40} {'network':26} {'val % [range]':>20} {'last-10 swing':>13} {'climb':>6} {'epochs':>7} "
          f"{'CPU s/run':>10} {'epochs x':>8} {'CPU x':>6} failed")
    for r in rows:
        b = base[r.network]
        print(f"{r.recipe:40} {r.network:26} {_pm(r.val):>20} {np.mean(r.swing):13.1f} {np.mean(r.climb):6.1f} "
              f"{np.mean(r.epochs):7.0f} "
              f"{r.cpu:10.1f} {np.mean(r.epochs) / np.mean(b.epochs):8.2f} {r.cpu / b.cpu:6.2f} {r.failed}")


def print_test(rows: Sequence[Row]) -> None:
    print(f"\n{'recipe':40} {'network':26} {'test % [range over seeds]':>26}")
    for r in rows:
        print(f"{r.recipe:40} {r.network:26} {_pm(r.test):>26}")


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--preset", choices=("smoke", "paper"), default="smoke", help="data set (default: smoke)")
    p.add_argument("--seeds", type=int, default=2, help="seeds per recipe and network on the screen (default: 2)")
    p.add_argument("--confirm", action="store_true", help="confirm the choice on the networks of CONFIRM")
    p.add_argument("--confirm-seeds", type=int, default=3, help="seeds of the confirmation (default: 3)")
    p.add_argument("--recipes", nargs="*", default=list(CANDIDATES), help="candidate names (default: all)")
    p.add_argument("--data-dir", type=Path, default=Path("data"), help="cache folder (default: data)")
    p.add_argument("--workers", type=int, default=0, help="training processes (default: one per CPU)")
    p.add_argument("--json", type=Path, help="also write every row here")
    a = p.parse_args(argv)
    unknown = [n for n in a.recipes if n not in CANDIDATES]
    if unknown or BASELINE not in a.recipes:
        print(f"bench_recipe: unknown recipes {unknown}; the baseline {BASELINE!r} must be one", file=sys.stderr)
        return 2
    smoke = a.preset == "smoke"
    ds = synth.dataset(a.preset, seed=0, data_dir=a.data_dir)
    seeds = tuple(range(a.seeds))
    t0 = time.perf_counter()
    rows = measure(ds, plan(a.recipes, SCREEN, seeds, smoke), a.data_dir, a.workers or None)
    print(f"\n{a.preset} data set ({len(ds.train.y)} training throws), {len(seeds)} seeds, screened in "
          f"{time.perf_counter() - t0:.0f} s wall; settled = on every network, a last-{LAST}-epoch swing <= {SETTLED} "
          f"points and a climb <= {CLIMB} point from the {LAST} epochs before")
    print_validation(rows)
    confirmed: list[Row] = []
    if a.confirm:  # every recipe that settles, on the other networks: what each costs the whole study
        c_seeds = tuple(range(a.confirm_seeds))
        settled, _ = settled_recipes(rows)
        confirmed = measure(ds, plan(list(dict.fromkeys((BASELINE, *settled))), CONFIRM, c_seeds, smoke),
                            a.data_dir, a.workers or None)
        print(f"\nconfirmation, {len(c_seeds)} seeds, every recipe that settles:")
        print_validation(confirmed)
    chosen, why = choose(rows, confirmed)
    print(f"\nchosen on validation: {chosen}")
    for name, reason in why.items():
        print(f"  {name}: {reason}")
    print_test(rows)
    if confirmed:
        print_test(confirmed)
    if a.json:
        a.json.write_text(json.dumps({"preset": a.preset, "chosen": chosen, "why": why,
                                      "rows": [dataclasses.asdict(r) for r in rows + confirmed]}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
