"""The cached experiment runs behind Table 1 and the length figure."""

import dataclasses
import json

import model_toys
import numpy as np
import pytest

from study import experiments, presets
from study.errors import ConfigError
from study.learn import train
from study.learn.metrics import Interval

TINY = experiments.Preset(
    name="tiny", length=0.5, lrs=(1e-2,), truncations=(5, 15), dropouts=(0.2,), batch_sizes=(8,),
    grid_seeds=(0, 1), seeds=(0, 1), lengths=(0.3, 0.5), length_seeds=(0,), max_epochs=1, patience=1, min_epochs=0,
    long_lengths=(0.5,), protocol_seeds=(0,),
)


@pytest.fixture(scope="module")
def ds():
    return model_toys.dataset(n=16, T=20)




@pytest.mark.slow
def test_pipeline_rows_and_cache(tmp_path, ds, monkeypatch):
    one_cell = dataclasses.replace(TINY, cells=("peephole",))
    grid = experiments.grid(ds, one_cell, "peephole", tmp_path, progress=False)
    assert [(r["truncation"], r["seed"]) for r in grid] == [(5, 0), (5, 1), (15, 0), (15, 1)]
    assert all("accuracy" not in r for r in grid), "the grid never scores the test split"
    points = experiments.grid_points(grid)
    assert [(r["truncation"], r["n"]) for r in points] == [(5, 2), (15, 2)]
    cfg = experiments.best_config(grid, one_cell)
    best = max(points, key=lambda r: r["val_mean"])
    assert cfg.dims == "z" and cfg.truncation == best["truncation"] and cfg.max_epochs == 1, "chosen by the mean"
    seeds = experiments.seed_runs(ds, cfg, one_cell, tmp_path, progress=False)
    assert [(r["dims"], r["seed"]) for r in seeds] == [("z", 0), ("z", 1), ("xyz", 0), ("xyz", 1)]
    assert all(0 <= r["accuracy"] <= 1 and r["correct"].shape == (16,) for r in seeds)
    lengths = experiments.length_sweep(ds, cfg, one_cell, tmp_path, progress=False)
    assert [(r["dims"], r["length"], r["frames"]) for r in lengths] == [
        ("z", 0.3, 9), ("z", 0.5, 15), ("xyz", 0.3, 9), ("xyz", 0.5, 15)]
    n_trained = len(list((tmp_path / "models").iterdir()))
    assert experiments.n_models(dataclasses.replace(one_cell, long_lengths=(), protocol_seeds=())) == n_trained + 0
    long = experiments.long_memory(ds, cfg, one_cell, tmp_path, progress=False)
    assert [(r["dims"], r["length"], r["truncation"]) for r in long] == [("z", 0.5, 15), ("xyz", 0.5, 15)], \
        "the long-memory variant back-propagates through every frame of the input"
    configs = [json.loads(f.read_text())["config"] for f in (tmp_path / "runs").glob("*.json")]
    assert sum(c["forget_init"] == "chrono" for c in configs) == 2, "with chrono-initialised forget gates"

    def no_training(*a, **k):
        raise AssertionError("a cached run was retrained")

    monkeypatch.setattr(train, "fit", no_training)
    again = experiments.seed_runs(ds, cfg, one_cell, tmp_path, progress=False)
    assert [{k: v for k, v in r.items() if k != "correct"} for r in again] == \
        [{k: v for k, v in r.items() if k != "correct"} for r in seeds]
    assert experiments.grid(ds, one_cell, "peephole", tmp_path, progress=False) == grid
    assert not list((tmp_path / "runs").glob(".*tmp"))


def test_grid_is_chosen_by_the_mean_over_seeds_not_one_lucky_run():
    rows = [{"cell": "peephole", "lr": lr, "truncation": 30, "dropout": 0.2, "batch_size": 32, "seed": s,
             "val_accuracy": acc, "val_loss": 0.5, "failed": False, "diverged_epoch": None, "epochs": 40}
            for lr, accs in ((1e-3, (0.80, 0.80, 0.80)), (3e-3, (0.95, 0.55, 0.56))) for s, acc in enumerate(accs)]
    assert experiments.best_config(rows, TINY).lr == 1e-3  # 3e-3 has the best single run, 1e-3 the best mean
    points = {r["lr"]: r for r in experiments.grid_points(rows)}
    assert points[3e-3]["val_std"] == pytest.approx(np.std([0.95, 0.55, 0.56], ddof=1))


@pytest.mark.slow
def test_test_run_scores_the_kept_model_of_the_same_run_without_test(tmp_path, ds, monkeypatch):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    trained = experiments.run(ds, cfg, tmp_path / "a", test=True)  # trained from scratch
    experiments.run(ds, cfg, tmp_path / "b", test=False)

    def no_training(*a, **k):
        raise AssertionError("the kept model should have been scored, not retrained")

    monkeypatch.setattr(train, "fit", no_training)
    scored = experiments.run(ds, cfg, tmp_path / "b", test=True)
    assert scored["test"] == trained["test"] and scored["val_accuracy"] == trained["val_accuracy"]
    assert scored["key"] == trained["key"] and scored["history"] == trained["history"]
    assert experiments.cached(ds, cfg, tmp_path / "b", test=True) == scored


@pytest.mark.slow
def test_run_record_and_key(tmp_path, ds):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    rec = experiments.run(ds, cfg, tmp_path)
    saved = json.loads((tmp_path / "runs" / f"{rec['key']}.json").read_text())
    assert saved == rec and rec["test"]["n"] == 16 and len(rec["history"]) == rec["epochs_run"]
    assert len(rec["test"]["p_heavy"]) == 16 and rec["format"] == experiments.RUN_FORMAT
    assert rec["failed"] in (True, False) and rec["diverged_epoch"] is None
    keys = {experiments.run_key(ds, cfg, True), experiments.run_key(ds, cfg, False),
            experiments.run_key(ds, dataclasses.replace(cfg, seed=1), True),
            experiments.run_key(model_toys.dataset(n=16, T=20, key="other"), cfg, True)}
    assert len(keys) == 4
    tm = train.load(experiments.model_dir(ds, cfg, tmp_path))  # the run left its model for reuse
    assert tm.config == cfg and train.evaluate(tm, ds.test) == {k: v for k, v in rec["test"].items() if k != "p_heavy"}
    (tmp_path / "runs" / f"{rec['key']}.json").write_text("{broken")
    again = experiments.run(ds, cfg, tmp_path)
    assert again["test"] == rec["test"], "a damaged cache entry is retrained, with the same result"


@pytest.mark.slow
def test_ablation_and_baseline(tmp_path, ds):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    winners = {c: dataclasses.replace(cfg, lr=lr) for c, lr in zip(TINY.cells, (1e-2, 3e-3, 1e-3))}
    rows = experiments.ablation(ds, winners, dataclasses.replace(TINY, seeds=(0,)), tmp_path, progress=False)
    assert [r["cell"] for r in rows] == ["peephole", "no-peephole", "gru"]
    recs = {json.loads(f.read_text())["config"]["cell"]: json.loads(f.read_text())["config"]["lr"]
            for f in (tmp_path / "runs").glob("*.json")}
    assert recs == {"peephole": 1e-2, "no-peephole": 3e-3, "gru": 1e-3}, "each cell at its own winner"
    base = experiments.baseline_runs(ds, TINY)
    assert [r["dims"] for r in base] == ["z", "xyz"] and all(0 <= r["accuracy"] <= 1 for r in base)


def test_summarise():
    rows = [{"dims": "z", "accuracy": a, "failed": a < 0.6} for a in (0.5, 0.8, 0.9)] + [{"dims": "xyz", "accuracy": 0.5}]
    s = {r["dims"]: r for r in experiments.summarise(rows, ("dims",))}
    assert s["z"]["n"] == 3 and s["z"]["mean"] == pytest.approx(2.2 / 3) and s["z"]["best"] == 0.9
    assert s["z"]["std"] == pytest.approx(np.std([0.5, 0.8, 0.9], ddof=1)) and s["xyz"]["std"] == 0.0
    assert s["z"]["failed"] == 1 and "interval" not in s["z"]  # no per-trajectory scores: no interval
    rng = np.random.default_rng(0)
    scored = [{"dims": "z", "accuracy": c.mean(), "correct": c} for c in (rng.random(100) < 0.8 for _ in range(3))]
    iv = experiments.summarise(scored, ("dims",))[0]["interval"]
    assert iv.lo < iv.value < iv.hi and "3 seeds" in iv.method


def test_presets():
    paper = experiments.preset("paper")
    assert len(paper.grid_seeds) >= 3 and len(paper.seeds) >= 5 and paper.n_grid >= 2
    assert paper.min_epochs >= 20 and paper.max_epochs > 2 * paper.min_epochs
    assert experiments.preset("smoke").max_epochs < paper.max_epochs
    assert set(experiments.PRESETS) == set(presets.NAMES)
    with pytest.raises(ConfigError, match="preset"):
        experiments.preset("huge")


def test_long_input_effect():
    def row(L, m, half=0.01):
        return {"dims": "z", "length": L, "mean": m, "interval": Interval(m, m - half, m + half, "x")}

    e = experiments.long_input_effect([row(1, 0.7), row(2, 0.8), row(4, 0.7)], "z")
    assert e["best_length"] == 2 and e["last_length"] == 4 and e["hurts"]
    assert not experiments.long_input_effect([row(1, 0.7), row(2, 0.8), row(4, 0.79)], "z")["hurts"]  # overlap
    assert not experiments.long_input_effect([row(L, 0.6 + 0.05 * L) for L in (1, 2, 4)], "z")["hurts"]


def test_markdown_table():
    from study import tables

    md = tables.markdown([{"a": 0.8123, "b": "x"}], {"a": "acc", "b": "name"}, {"a": tables.pct})
    assert md.splitlines() == ["| acc | name |", "|---|---|", "| 81.2 % | x |"]
    assert tables.pct_pm(0.8, 0.0123) == "80.0 ± 1.2 %"


@pytest.mark.slow
def test_parallel_runs_equal_sequential_runs(tmp_path, ds):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    seq = experiments.seed_runs(ds, cfg, TINY, tmp_path / "a", progress=False, workers=1)
    par = experiments.seed_runs(ds, cfg, TINY, tmp_path / "b", progress=False, workers=2)
    strip = lambda rows: [{k: v for k, v in r.items() if k not in ("seconds", "correct")} for r in rows]  # noqa: E731
    assert strip(par) == strip(seq)
    assert all((a["correct"] == b["correct"]).all() for a, b in zip(par, seq))
    for f in (tmp_path / "a" / "runs").glob("*.json"):
        a, b = json.loads(f.read_text()), json.loads((tmp_path / "b" / "runs" / f.name).read_text())
        a.pop("train_seconds"), b.pop("train_seconds")
        assert a == b, "the same history, bit for bit, from a worker process"
