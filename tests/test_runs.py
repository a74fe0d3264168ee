"""The cached experiment runs behind Table 1 and the length figure, through the runner a chapter opens."""

import dataclasses
import json
from pathlib import Path

import model_toys
import numpy as np
import pytest

from study import runs
from study.chapters import cues, length, realworld, table1
from study.core import presets
from study.core.errors import ConfigError
from study.learn import train
from study.learn.metrics import Interval, bootstrap_accuracy
from study.report import text
from study.runs import cluster, paper, records, schedule, stats
from study.runs.runner import Runner
from study.runs.runtable import Run, Runs

TINY = runs.Preset(
    name="tiny", length=0.5, lrs=(1e-2,), truncations=(5, 15), dropouts=(0.2,), batch_sizes=(8,),
    grid_seeds=(0, 1), seeds=(0, 1), lengths=(0.3, 0.5), length_seeds=(0,), epochs=1, patience=1, min_epochs=0,
    long_lengths=(0.5,), protocol_seeds=(0,),
)


@pytest.fixture(scope="module")
def ds():
    return model_toys.dataset(n=16, T=20)


def runner(ds, preset, folder: Path, workers: int = 1, **kw) -> Runner:
    return Runner(ds, preset, folder.resolve(), workers=workers, **kw)




@pytest.mark.slow
def test_pipeline_rows_and_cache(tmp_path, ds, monkeypatch):
    one_cell = dataclasses.replace(TINY, cells=("peephole",))
    r = runner(ds, one_cell, tmp_path)
    grid = r.grid("peephole")
    assert [(g.config.truncation, g.seed) for g in grid] == [(5, 0), (5, 1), (15, 0), (15, 1)]
    assert all(g.accuracy is None and g.correct is None for g in grid), "the grid never scores the test split"
    points = paper.grid_points(grid)
    assert [(g.config.truncation, g.n) for g in points] == [(5, 2), (15, 2)]
    cfg = r.table1_config()
    best = max(points, key=lambda g: g.val_mean)
    assert cfg.dims == "z" and cfg.truncation == best.config.truncation and cfg.epochs == 1, "chosen by the mean"
    seeds = r.seed_runs(cfg)
    assert [(g.get("dims"), g.seed) for g in seeds] == [("z", 0), ("z", 1), ("xyz", 0), ("xyz", 1)]
    assert all(0 <= g.accuracy <= 1 and g.correct.shape == (16,) for g in seeds)
    assert seeds.where(dims="z").correct().shape == (2, 16) and len(seeds.groups("dims")) == 2
    lengths = length.length_runs(r, cfg)
    assert [(g.get("dims"), g.get("length"), g.get("frames")) for g in lengths] == [
        ("z", 0.3, 9), ("z", 0.5, 15), ("xyz", 0.3, 9), ("xyz", 0.5, 15)]
    n_trained = len(list((tmp_path / "models").iterdir()))
    assert r.plan.n_models == n_trained, "the plan counts every distinct model the runner was asked for"
    again = runner(ds, one_cell, tmp_path)  # every model cached now: asked for the same, it counts the same
    again.trained(cfg)
    assert again.plan.n_models == 1, "a model loaded from the cache is in the plan as one trained afresh"
    long = length.long_memory_runs(r, cfg)
    assert [(g.get("dims"), g.get("length"), g.get("truncation")) for g in long] == [("z", 0.5, 15), ("xyz", 0.5, 15)], \
        "the long-memory variant back-propagates through every frame of the input"
    configs = [json.loads(f.read_text())["config"] for f in (tmp_path / "runs").glob("*.json")]
    assert sum(c["forget_init"] == "chrono" for c in configs) == 2, "with chrono-initialised forget gates"

    def no_training(*a, **k):
        raise AssertionError("a cached run was retrained")

    monkeypatch.setattr(train, "fit", no_training)
    again = r.seed_runs(cfg)
    strip = lambda rs: [{k: v for k, v in vars(g).items() if k != "correct"} for g in rs]  # noqa: E731
    assert strip(again) == strip(seeds) and all((a.correct == b.correct).all() for a, b in zip(again, seeds))
    assert strip(r.grid("peephole")) == strip(grid)
    assert not list((tmp_path / "runs").glob(".*tmp"))


def test_the_plan_counts_distinct_models_and_sums_their_training_time(tmp_path, ds):
    cfg = TINY.base_config()
    plan = schedule.Plan(tmp_path / "plan.jsonl")
    for c in paper.seed_configs(cfg, TINY.seeds):
        plan.add(ds, c, tmp_path, test=True)
    assert plan.n_models == 4
    plan.add(ds, paper.seed_configs(cfg, (0,))[0], tmp_path, test=False)  # the same model, validation only
    assert plan.n_models == 4
    plan.add(ds, dataclasses.replace(cfg, seed=9), tmp_path, test=True)  # one run more: one model more
    assert plan.n_models == 5
    key = records.run_key(ds, dataclasses.replace(cfg, seed=9), True)
    records.record_path(tmp_path, key).parent.mkdir(parents=True)
    records.record_path(tmp_path, key).write_text(json.dumps({"train_seconds": 2.5, "epochs_run": 7}))
    assert cluster.plan_totals([tmp_path / "plan.jsonl", tmp_path / "absent.jsonl"]) == {
        "models": 5.0, "cpu_seconds": 2.5, "epochs": 7.0, "failed": 0.0}
    other = schedule.Plan(tmp_path / "other.jsonl")  # a second chapter asks for one model of the first and one more
    other.add(ds, dataclasses.replace(cfg, seed=9), tmp_path, test=True)
    other.add(ds, dataclasses.replace(cfg, seed=10), tmp_path, test=True)
    by = cluster.plan_by_part([tmp_path / "plan.jsonl", tmp_path / "other.jsonl"])
    assert {k: v["models"] for k, v in by.items()} == {"plan": 5.0, "other": 1.0}  # each model counted once
    assert by["plan"]["epochs"] == 7.0 and by["other"]["epochs"] == 0.0
    records.record_path(tmp_path, key).write_text(json.dumps({"train_seconds": 2.5, "cpu_seconds": 4.0,
                                                              "epochs_run": 7}))
    assert cluster.plan_totals([tmp_path / "plan.jsonl"])["cpu_seconds"] == 4.0  # process time where it was kept


def _run(cfg: train.TrainConfig, val_accuracy: float = 0.7, accuracy: float | None = None, **kw) -> Run:
    return Run(cfg, val_accuracy, 0.5, 40, 30, 1.0, failed=False, accuracy=accuracy, **kw)


def test_grid_is_chosen_by_the_mean_over_seeds_not_one_lucky_run():
    base = train.TrainConfig(truncation=30)
    rows = Runs(_run(dataclasses.replace(base, lr=lr, seed=s), acc)
                for lr, accs in ((1e-3, (0.80, 0.80, 0.80)), (3e-3, (0.95, 0.55, 0.56))) for s, acc in enumerate(accs))
    assert paper.best_config(rows, TINY).lr == 1e-3  # 3e-3 has the best single run, 1e-3 the best mean
    points = {r.config.lr: r for r in paper.grid_points(rows)}
    assert points[3e-3].val_std == pytest.approx(np.std([0.95, 0.55, 0.56], ddof=1))
    assert points[1e-3].same_point(dataclasses.replace(base, lr=1e-3, seed=7, dims="xyz")), "the seed is no point"


@pytest.mark.slow
def test_test_run_scores_the_kept_model_of_the_same_run_without_test(tmp_path, ds, monkeypatch):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    trained = records.run(ds, cfg, tmp_path / "a", test=True)  # trained from scratch
    records.run(ds, cfg, tmp_path / "b", test=False)

    def no_training(*a, **k):
        raise AssertionError("the kept model should have been scored, not retrained")

    monkeypatch.setattr(train, "fit", no_training)
    scored = records.run(ds, cfg, tmp_path / "b", test=True)
    assert scored["test"] == trained["test"] and scored["val_accuracy"] == trained["val_accuracy"]
    assert scored["key"] == trained["key"] and scored["history"] == trained["history"]
    assert records.cached(ds, cfg, tmp_path / "b", test=True) == scored


@pytest.mark.slow
def test_run_record_and_key(tmp_path, ds):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    rec = records.run(ds, cfg, tmp_path)
    saved = json.loads((tmp_path / "runs" / f"{rec['key']}.json").read_text())
    assert saved == rec and rec["test"]["n"] == 16 and len(rec["history"]) == rec["epochs_run"]
    assert len(rec["test"]["p_heavy"]) == 16 and rec["format"] == records.RUN_FORMAT
    assert rec["failed"] in (True, False) and rec["diverged_epoch"] is None
    keys = {records.run_key(ds, cfg, True), records.run_key(ds, cfg, False),
            records.run_key(ds, dataclasses.replace(cfg, seed=1), True),
            records.run_key(model_toys.dataset(n=16, T=20, key="other"), cfg, True)}
    assert len(keys) == 4
    tm = train.load(records.model_dir(ds, cfg, tmp_path))  # the run left its model for reuse
    assert tm.config == cfg and train.evaluate(tm, ds.test) == {k: v for k, v in rec["test"].items() if k != "p_heavy"}
    (tmp_path / "runs" / f"{rec['key']}.json").write_text("{broken")
    again = records.run(ds, cfg, tmp_path)
    assert again["test"] == rec["test"], "a damaged cache entry is retrained, with the same result"


@pytest.mark.slow
def test_ablation_and_baseline(tmp_path, ds):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    winners = {c: dataclasses.replace(cfg, lr=lr) for c, lr in zip(TINY.cells, (1e-2, 3e-3, 1e-3))}
    r = runner(ds, dataclasses.replace(TINY, seeds=(0,)), tmp_path)
    rows = table1.ablation_runs(r, winners)
    assert rows.values("cell") == ["peephole", "no-peephole", "gru"]
    recs = {json.loads(f.read_text())["config"]["cell"]: json.loads(f.read_text())["config"]["lr"]
            for f in (tmp_path / "runs").glob("*.json")}
    assert recs == {"peephole": 1e-2, "no-peephole": 3e-3, "gru": 1e-3}, "each cell at its own winner"
    base = table1.baseline_runs(r)
    assert list(base) == ["z", "xyz"] and all(0 <= b.accuracy <= 1 and b.correct.shape == (16,) for b in base.values())


def test_summarise_and_the_run_table():
    z, xyz = train.TrainConfig(dims="z"), train.TrainConfig(dims="xyz")
    rows = Runs([Run(dataclasses.replace(z, seed=k), 0.7, 0.5, 40, 30, 1.0, failed=a < 0.6, accuracy=a)
                 for k, a in enumerate((0.5, 0.8, 0.9))] + [_run(xyz, accuracy=0.5)])
    s = {r.keys["dims"]: r for r in stats.summarise(rows, ("dims",))}
    assert s["z"].n == 3 and s["z"].mean == pytest.approx(2.2 / 3) and s["z"].max == 0.9
    assert s["z"].std == pytest.approx(np.std([0.5, 0.8, 0.9], ddof=1)) and s["xyz"].std == 0.0
    assert s["z"].failed == 1 and s["z"].interval is None  # no per-trajectory scores: no interval
    assert rows.where(dims="z").seeds == [0, 1, 2] and rows.where(dims="z", seed=1).one().accuracy == 0.8
    with pytest.raises(ConfigError, match="validation only"):
        rows.correct()
    with pytest.raises(ConfigError, match="neither a label"):
        rows[0].get("colour")
    rng = np.random.default_rng(0)
    scored = Runs(_run(dataclasses.replace(z, seed=k), accuracy=c.mean(), correct=c)
                  for k, c in enumerate(rng.random(100) < 0.8 for _ in range(3)))
    iv = stats.summary(scored).interval
    assert iv.lo < iv.value < iv.hi and "3 seeds" in iv.method


def test_the_run_validation_picks_is_one_statistic_over_one_data_set_or_several():
    rng = np.random.default_rng(1)
    z = train.TrainConfig(dims="z")

    def data_set(vals):  # seed 1 validates best; seed 0 is best on the test split
        return Runs(_run(dataclasses.replace(z, seed=k), v, accuracy=c.mean(), correct=c)
                    for k, (v, c) in enumerate(zip(vals, (rng.random(200) < p for p in (0.9, 0.7, 0.6)))))

    one = stats.validation_pick([data_set((0.6, 0.8, 0.7))])
    assert [r.seed for r in one.picked] == [1]
    assert one.interval == bootstrap_accuracy(one.picked[0].correct), "over one data set: the run's own bootstrap"
    three = stats.validation_pick([data_set((0.6, 0.8, 0.7)) for _ in range(3)])
    assert [r.seed for r in three.picked] == [1, 1, 1] and "hierarchical" in three.interval.method
    assert three.interval.value == pytest.approx(np.mean([r.accuracy for r in three.picked]))


def test_presets():
    big = runs.preset("paper")
    assert len(big.grid_seeds) >= 3 and len(big.seeds) >= 5 and big.n_grid() >= 2 and big.n_grid('gru') >= big.n_grid()
    assert big.min_epochs >= 20 and big.epochs > 2 * big.min_epochs
    assert runs.preset("smoke").epochs < big.epochs
    assert big.base_config() == train.TrainConfig(), "the paper preset trains with TrainConfig's own protocol"
    assert big.base_config() in paper.grid_configs(big), "the grid holds the defaults"
    assert set(runs.PRESETS) == set(presets.NAMES)
    with pytest.raises(ConfigError, match="preset"):
        runs.preset("huge")


def test_long_input_effect():
    def row(L, m, half=0.01):
        return stats.Summary({"dims": "z", "length": L}, 2, m, 0.0, m, m, 0, 0, 0, Interval(m, m - half, m + half, "x"))

    e = stats.long_input_effect([row(1, 0.7), row(2, 0.8), row(4, 0.7)], "z")
    assert e.best_length == 2 and e.last_length == 4 and e.hurts
    assert not stats.long_input_effect([row(1, 0.7), row(2, 0.8), row(4, 0.79)], "z").hurts  # overlap
    assert not stats.long_input_effect([row(L, 0.6 + 0.05 * L) for L in (1, 2, 4)], "z").hurts


def test_markdown_table():
    md = text.markdown([{"a": 0.8123, "b": "x"}], {"a": "acc", "b": "name"}, {"a": text.pct})
    assert md.splitlines() == ["| acc | name |", "|---|---|", "| 81.2 % | x |"]
    assert text.Table([{"a": 0.8123, "b": "x"}], {"a": "acc", "b": "name"}, {"a": text.pct}).markdown() == md
    assert text.pct_pm(0.8, 0.0123) == "80.0 ± 1.2 %"


@pytest.mark.slow
def test_parallel_runs_equal_sequential_runs(tmp_path, ds):
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    seq = runner(ds, TINY, tmp_path / "a", workers=1).seed_runs(cfg)
    par = runner(ds, TINY, tmp_path / "b", workers=2).seed_runs(cfg)
    strip = lambda rows: [{k: v for k, v in vars(r).items() if k not in ("seconds", "correct")} for r in rows]  # noqa: E731
    assert strip(par) == strip(seq)
    assert all((a.correct == b.correct).all() for a, b in zip(par, seq))
    for f in (tmp_path / "a" / "runs").glob("*.json"):
        a, b = json.loads(f.read_text()), json.loads((tmp_path / "b" / "runs" / f.name).read_text())
        a.pop("train_seconds"), b.pop("train_seconds"), a.pop("cpu_seconds"), b.pop("cpu_seconds")
        assert a == b, "the same history, bit for bit, from a worker process"


@pytest.mark.slow  # starts a Dask LocalCluster and trains on it
def test_a_dask_cluster_trains_the_same_records_as_the_local_pool(tmp_path, smoke_dataset):
    """The smoke Table 1, trained into one fresh folder on a LocalCluster and into another on the local process
    pool: the same records, bit for bit (train_seconds aside), under the same keys."""
    smoke = runs.preset("smoke")
    cfg = smoke.base_config()
    pool = runner(smoke_dataset, smoke, tmp_path / "pool", workers=2).seed_runs(cfg)
    dask = runner(smoke_dataset, smoke, tmp_path / "dask", workers=2, scheduler="local").seed_runs(cfg)
    assert dask.values("accuracy") == pool.values("accuracy")
    names = sorted(f.name for f in (tmp_path / "pool" / "runs").glob("*.json"))
    assert names and names == sorted(f.name for f in (tmp_path / "dask" / "runs").glob("*.json"))
    for name in names:
        a, b = (json.loads((tmp_path / w / "runs" / name).read_text()) for w in ("pool", "dask"))
        a.pop("train_seconds"), b.pop("train_seconds"), a.pop("cpu_seconds"), b.pop("cpu_seconds")
        assert a == b
    c = schedule.client("local", 2)
    assert c.scheduler.address.startswith("tcp://127.0.0.1:"), "a LocalCluster listens on the loopback only"
    assert all(w.startswith("tcp://127.0.0.1:") for w in c.scheduler_info()["workers"])


def test_a_worker_that_computes_another_key_refuses(tmp_path, ds):
    cfg = TINY.base_config()
    with pytest.raises(schedule.WorkerError, match="computes run key .* where the submitter computed wrong"):
        schedule.stack_task([(ds, cfg, True, "wrong")], str(tmp_path))
    assert not (tmp_path / "runs").exists(), "it writes nothing"


@pytest.mark.slow  # trains twenty tiny models
def test_the_recommended_model_is_the_best_candidate_on_observed_validation_throws(tmp_path):
    from study.methods import recommend
    from study.runs import measured
    from study.simulate import observe

    toy = model_toys.dataset(n=40, T=20)
    r = runner(toy, TINY, tmp_path)
    cfg = dataclasses.replace(TINY.base_config(), truncation=5, batch_size=8)
    ob = observe.Observation(noise=0.01, drop=0.1)
    floor = observe.Observation(noise=0.03, drop=0.05)  # the floor path's error, as its fit would give it
    cfgs = {"positions": cfg, "velocity": dataclasses.replace(cfg, inputs="velocity")}
    assert list(recommend.candidates(r, cfgs, ob)) == [f"{i}, {t}" for i in ("positions", "velocity")
                                                       for t in ("exact", "randomised", "any-camera")]
    cands = recommend.candidates(r, cfgs, ob, floor)
    assert list(cands) == [f"{i}, {t}" for i in ("positions", "velocity")
                           for t in ("exact", "randomised", "any-camera", "floor", "floor-fixed")]
    assert cands["velocity, randomised"].observe == "randomised" and cands["velocity, randomised"].observe_noise == 0.01
    assert cands["velocity, any-camera"] == dataclasses.replace(cands["velocity, randomised"], observe="any-camera")
    assert cands["positions, floor"].observe == "randomised" and cands["positions, floor"].observe_noise == 0.03
    assert cands["positions, floor-fixed"] == dataclasses.replace(cands["positions, floor"], observe="fixed")
    assert all(recommend.kind(n) == measured.kind(c) for n, c in cands.items() if ", floor" not in n)
    assert recommend.kind("positions, floor") == "positions-floor", "named apart from the calibrated randomised kind"
    assert recommend.kind("velocity, floor-fixed") == "velocity-floor-fixed", "and from the fixed tracker error's"
    rec = recommend.recommended(r, cands, seeds=(0, 1), ob=ob, floor=floor)
    choice, val, user, models = rec.choice, rec.val, rec.val_user, rec.models
    assert set(val) == set(user) == set(rec.val_floor) == set(models) == set(cands)
    assert choice == max(user, key=lambda k: user[k].value)
    assert rec.floor_choice == max(rec.val_floor, key=lambda k: rec.val_floor[k].value)
    assert val != user, "scored through the calibrated tracker and as a user's camera gives the throws"
    assert rec.model is models[choice]
    assert [m.config for m in models[choice].members] == [dataclasses.replace(cands[choice], seed=s) for s in (0, 1)]
    assert r.plan.n_models == 20 and all(0 <= v.lo <= v.value <= v.hi <= 1 for v in val.values())
    assert recommend.recommended(r, cands, seeds=(0,), ob=ob).floor_choice is None, "no floor path: no floor model"
    with pytest.raises(ConfigError, match="seeds is empty"):
        recommend.recommended(r, cands, seeds=(), ob=ob)


def test_an_in_memory_dataset_is_saved_once_for_the_workers(tmp_path, ds):
    r = runner(ds, TINY, tmp_path)
    saved = cues.saved(r, ds, "mixed")
    assert saved.path == tmp_path / f"mixed-{ds.key}.npz" and saved.key == ds.key
    np.testing.assert_array_equal(saved.train.x, ds.train.x)
    mtime = saved.path.stat().st_mtime_ns
    assert cues.saved(r, ds, "mixed").path.stat().st_mtime_ns == mtime, "written once"
    assert r.on(saved).dataset is saved and r.on(saved).plan is r.plan


def test_a_failed_run_is_listed_with_the_reason_the_book_means_it_to_fail_or_as_a_failure_by_chance(tmp_path):
    import dataclasses as dc

    from study.learn.config import TrainConfig
    from study.runs import cluster, failures

    def record(name: str, cfg: TrainConfig, failed: bool) -> str:
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps({"config": dc.asdict(cfg), "failed": failed, "best_epoch": 3, "epochs_run": 50}))
        return str(path)

    first = TrainConfig(forget_bias=0.0, min_epochs=0, clip_norm=0.0)
    long = TrainConfig(length=6.0)
    plan = tmp_path / "table1.jsonl"
    plan.write_text("".join(json.dumps({"model": m, "record": record(m, c, f)}) + "\n" for m, c, f in (
        ("first", first, True), ("long", long, True), ("chance", TrainConfig(seed=3), True),
        ("fine", TrainConfig(), False))))
    failed = cluster.plan_listed([plan])["failed_runs"]
    assert [f["model"] for f in failed] == ["first", "long", "chance"] and {f["chapter"] for f in failed} == {"table1"}
    assert "first protocol" in failed[0]["reason"] and "Figure 4" in failed[1]["reason"]
    assert [f["model"] for f in failures.by_chance(failed)] == ["chance"]
    chrono = dc.asdict(dc.replace(long, forget_init="chrono", truncation=180))
    assert failures.reason(chrono, 30.0) == failures.BY_CHANCE, "the memory spans the input: a failure is chance's"
    assert "truncated" in failures.reason({**chrono, "truncation": 90}, 30.0), "90 of 180 frames back-propagated"
    assert failures.reason({**chrono, "truncation": 90}) == failures.BY_CHANCE, "no frame rate recorded: cannot say"
    assert "shortest input" in failures.reason(dc.asdict(TrainConfig(length=0.5)), 30.0)
    assert failures.reason(dc.asdict(TrainConfig(length=3.0)), 30.0) == failures.BY_CHANCE, "Table 1's own: chance"


def test_a_failed_candidate_its_chapter_turned_down_is_listed_as_rejected_not_chance(tmp_path):
    import dataclasses as dc

    from study.learn.config import TrainConfig
    from study.runs import cluster, failures, schedule
    from study.simulate.data import Dataset, Split

    ds = Dataset(train=Split(np.zeros((4, 3, 3)), np.zeros(4, int), {}), test=Split(np.zeros((4, 3, 3)), np.zeros(4, int), {}),
                 fps=30.0)
    plan = schedule.Plan(tmp_path / "motion.jsonl")
    high, low = TrainConfig(cell="gru", lr=3e-3), TrainConfig(cell="gru", lr=1e-3)
    short = TrainConfig(cell="gru", lr=3e-3, length=0.5)
    for cfg in (high, low, short):
        plan.add(ds, cfg, tmp_path, True)
        record = Path(plan.models[schedule.run_key(ds, cfg, False, "cpu")])
        record.parent.mkdir(parents=True, exist_ok=True)
        record.write_text(json.dumps({"config": dc.asdict(cfg), "failed": True, "best_epoch": 0, "epochs_run": 100}))
    plan.reject(ds, high)
    plan.reject(ds, short)
    assert cluster.plan_totals([plan.path])["models"] == 3, "a rejection adds no model"
    failed = {(f["lr"], f["length"]): f["reason"] for f in cluster.plan_listed([plan.path])["failed_runs"]}
    assert failed[3e-3, 3.0] == failures.REJECTED and failed[1e-3, 3.0] == failures.BY_CHANCE, "the chosen stays chance's"
    assert "shortest input" in failed[3e-3, 0.5], "a designed failure keeps its reason"


def test_a_run_still_improving_when_its_epoch_budget_ran_out_is_listed_as_not_flattened(tmp_path):
    import dataclasses as dc

    from study.learn.config import TrainConfig
    from study.runs import cluster, failures

    def record(name: str, cfg: TrainConfig, curve: list[float]) -> str:
        path = tmp_path / f"{name}.json"
        history = [{"epoch": e, "val_accuracy": a} for e, a in enumerate(curve)]
        path.write_text(json.dumps({"config": dc.asdict(cfg), "failed": False, "best_epoch": len(curve) - 1,
                                    "epochs_run": len(curve), "val_accuracy": curve[-1], "history": history}))
        return str(path)

    climbing = [0.7 + 0.002 * e for e in range(150)]  # the GRU's best point: 3 points in the last 20 epochs
    saturated = [0.99 + 0.00005 * e for e in range(150)]  # velocity Z: its loss still falls, its accuracy is flat
    swinging = [0.8 + 0.03 * (e % 2) for e in range(150)]
    plan = tmp_path / "table1.jsonl"
    plan.write_text("".join(json.dumps({"model": m, "record": record(m, c, a)}) + "\n" for m, c, a in (
        ("climbing", TrainConfig(epochs=150), climbing), ("saturated", TrainConfig(epochs=150), saturated),
        ("swinging", TrainConfig(epochs=150), swinging), ("stopped", TrainConfig(epochs=150), climbing[:81]),
        ("cosine", TrainConfig(epochs=150, lr_schedule="cosine"), climbing))))
    got = cluster.plan_listed([plan])["unsettled_runs"]
    assert [u["model"] for u in got] == ["climbing", "swinging"] and got[0]["chapter"] == "table1"
    assert failures.swing_and_climb(climbing) == pytest.approx((1.8, 2.0))
