"""The cached experiment runs behind Table 1 and the length figure."""

import dataclasses
import json

import model_toys
import numpy as np
import pytest

from study import experiments
from study.errors import ConfigError
from study.learn import train

TINY = experiments.Preset(
    name="tiny", length=0.5, lrs=(1e-2,), truncations=(5, 15), dropouts=(0.2,), batch_sizes=(8,),
    seeds=(0, 1), lengths=(0.3, 0.5), length_seeds=(0,), max_epochs=1, patience=1,
)


@pytest.fixture(scope="module")
def ds():
    return model_toys.dataset(n=16, T=20)




@pytest.mark.slow
def test_pipeline_rows_and_cache(tmp_path, ds, monkeypatch):
    grid = experiments.grid(ds, TINY, tmp_path, progress=False)
    assert [(r["truncation"]) for r in grid] == [5, 15] and all("accuracy" not in r for r in grid), \
        "the grid never scores the test split"
    cfg = experiments.best_config(grid, TINY)
    assert cfg.dims == "z" and cfg.truncation in (5, 15) and cfg.max_epochs == 1
    seeds = experiments.seed_runs(ds, cfg, TINY, tmp_path, progress=False)
    assert [(r["dims"], r["seed"]) for r in seeds] == [("z", 0), ("z", 1), ("xyz", 0), ("xyz", 1)]
    assert all(0 <= r["accuracy"] <= 1 for r in seeds)
    lengths = experiments.length_sweep(ds, cfg, TINY, tmp_path, progress=False)
    assert [(r["dims"], r["length"], r["frames"]) for r in lengths] == [
        ("z", 0.3, 9), ("z", 0.5, 15), ("xyz", 0.3, 9), ("xyz", 0.5, 15)]
    n_files = len(list((tmp_path / "runs").glob("*.json")))
    assert n_files == 2 + 4 + 2  # the length sweep's 0.5 s runs are the seed runs' (cache hits)
    n_trained = len(list((tmp_path / "models").iterdir()))
    assert n_trained == n_files - 1, "the Z seed run at the grid seed scores the grid winner's model"
    assert experiments.n_models(dataclasses.replace(TINY, cells=("peephole",))) == n_trained
    control = experiments.full_bptt_control(ds, cfg, dataclasses.replace(TINY, control_lengths=(0.5,)), tmp_path,
                                            progress=False)
    assert [(r["dims"], r["length"], r["truncation"]) for r in control] == [("z", 0.5, 15), ("xyz", 0.5, 15)], \
        "the control back-propagates through every frame of the input"

    def no_training(*a, **k):
        raise AssertionError("a cached run was retrained")

    monkeypatch.setattr(train, "fit", no_training)
    assert experiments.seed_runs(ds, cfg, TINY, tmp_path, progress=False) == seeds
    assert experiments.grid(ds, TINY, tmp_path, progress=False) == grid
    assert not list((tmp_path / "runs").glob(".*tmp"))


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
    keys = {experiments.run_key(ds, cfg, True), experiments.run_key(ds, cfg, False),
            experiments.run_key(ds, dataclasses.replace(cfg, seed=1), True),
            experiments.run_key(model_toys.dataset(n=16, T=20, key="other"), cfg, True)}
    assert len(keys) == 4
    tm = train.load(experiments.model_dir(ds, cfg, tmp_path))  # the run left its model for reuse
    assert tm.config == cfg and train.evaluate(tm, ds.test) == rec["test"]
    (tmp_path / "runs" / f"{rec['key']}.json").write_text("{broken")
    again = experiments.run(ds, cfg, tmp_path)
    assert again["test"] == rec["test"], "a damaged cache entry is retrained, with the same result"


@pytest.mark.slow
def test_ablation_and_baseline(tmp_path, ds):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    rows = experiments.ablation(ds, cfg, dataclasses.replace(TINY, seeds=(0,)), tmp_path, progress=False)
    assert [r["cell"] for r in rows] == ["peephole", "no-peephole", "gru"]
    base = experiments.baseline_runs(ds, TINY)
    assert [r["dims"] for r in base] == ["z", "xyz"] and all(0 <= r["accuracy"] <= 1 for r in base)


def test_summarise():
    rows = [{"dims": "z", "accuracy": a} for a in (0.7, 0.8, 0.9)] + [{"dims": "xyz", "accuracy": 0.5}]
    s = {r["dims"]: r for r in experiments.summarise(rows, ("dims",))}
    assert s["z"]["n"] == 3 and s["z"]["mean"] == pytest.approx(0.8) and s["z"]["best"] == 0.9
    assert s["z"]["std"] == pytest.approx(np.std([0.7, 0.8, 0.9], ddof=1)) and s["xyz"]["std"] == 0.0


def test_presets():
    paper = experiments.preset("paper")
    assert paper.n_grid >= 16 and len(paper.seeds) >= 5 and len(paper.lengths) >= 8
    assert min(len(v) for v in (paper.lrs, paper.truncations, paper.dropouts, paper.batch_sizes)) >= 2
    assert experiments.preset("smoke").max_epochs < paper.max_epochs
    with pytest.raises(ConfigError, match="preset"):
        experiments.preset("huge")


def test_long_input_effect():
    s = [{"dims": "z", "length": L, "mean": m, "std": 0.01} for L, m in [(1, 0.7), (2, 0.8), (4, 0.7)]]
    e = experiments.long_input_effect(s, "z")
    assert e["best_length"] == 2 and e["last_length"] == 4 and e["hurts"]
    flat = [dict(r, mean=0.8) for r in s]
    assert not experiments.long_input_effect(flat, "z")["hurts"]
    rising = [dict(r, mean=0.6 + 0.05 * r["length"]) for r in s]
    assert not experiments.long_input_effect(rising, "z")["hurts"]


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
    strip = lambda rows: [{k: v for k, v in r.items() if k != "seconds"} for r in rows]  # noqa: E731
    assert strip(par) == strip(seq)
    for f in (tmp_path / "a" / "runs").glob("*.json"):
        a, b = json.loads(f.read_text()), json.loads((tmp_path / "b" / "runs" / f.name).read_text())
        a.pop("train_seconds"), b.pop("train_seconds")
        assert a == b, "the same history, bit for bit, from a worker process"
