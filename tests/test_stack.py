"""Many runs as one stack (study.learn.stack): a member's result does not depend on its stack, on either time loop."""

from __future__ import annotations

import dataclasses
import json

import pytest
import torch

from study.core import ticket
from study.learn import native, stack, train
from study.learn.config import TrainConfig
from study.runs import records, schedule

SMOKE = TrainConfig(length=1.0, epochs=4, patience=2, min_epochs=2, truncation=10)
"""A short training at the smoke data set's shape; every member below shares it but for seed, rate and dropout."""
OTHERS = [dataclasses.replace(SMOKE, seed=s, lr=lr, dropout=d, epochs=e, min_epochs=min(e, 2)) for s, lr, d, e in
          ((1, 3e-3, 0.2, 4), (2, 1e-3, 0.0, 2), (3, 1e-3, 0.5, 4), (4, 2e-3, 0.2, 1), (5, 1e-3, 0.2, 4),
           (6, 1e-3, 0.1, 3), (7, 3e-4, 0.2, 4))]
"""Other members: other seeds, learning rates, dropouts and epoch caps (so the stack shrinks as they stop)."""
RECIPE = dataclasses.replace(SMOKE, lr_schedule="cosine", warmup_epochs=1, epochs=3, average="ema", ema_decay=0.9)
"""A member on a cosine budget with a warm-up, validating and keeping the moving average of its weights."""


def _records(smoke_dataset, cfgs, tmp_path, name) -> list[dict]:
    jobs = [(smoke_dataset, c, True) for c in cfgs]
    out = records.train_stack(jobs, tmp_path / name)
    for rec in out:
        assert json.loads(records.record_path(tmp_path / name, rec["key"]).read_text()) == rec, "written as returned"
    return [{k: v for k, v in r.items() if k not in ("train_seconds", "cpu_seconds")} for r in out]


@pytest.mark.slow  # trains 12 smoke runs
@pytest.mark.parametrize("cell", ["peephole", "gru"])
def test_a_run_gives_the_same_record_alone_in_a_stack_of_3_and_of_8(smoke_dataset, tmp_path, cell):
    """Bit for bit, training times aside: each member its own seed, batch order, dropout masks, Adam and stop."""
    base = dataclasses.replace(SMOKE, cell=cell)
    others = [dataclasses.replace(c, cell=cell) for c in OTHERS]
    alone = _records(smoke_dataset, [base], tmp_path, "alone")[0]
    three = _records(smoke_dataset, [others[0], base, others[1]], tmp_path, "three")
    eight = _records(smoke_dataset, [*others[:4], base, *others[4:7]], tmp_path, "eight")
    assert three[1] == alone and eight[4] == alone
    assert three[0] == eight[0] and three[2] == eight[1], "the other members agree too"
    assert len({r["epochs_run"] for r in eight}) > 1, "members stopped at different epochs: the stack shrank"


@pytest.mark.slow  # trains 6 smoke runs
def test_a_recipe_member_is_its_own_run_and_leaves_the_others_theirs(smoke_dataset, tmp_path):
    """A cosine budget with warm-up and a weight average, alone and among members that stop early: bit for bit."""
    alone = _records(smoke_dataset, [RECIPE, SMOKE], tmp_path, "alone")
    mixed = _records(smoke_dataset, [OTHERS[0], RECIPE, SMOKE], tmp_path, "mixed")
    assert mixed[1] == alone[0] and mixed[2] == alone[1]
    assert alone[0]["epochs_run"] == RECIPE.epochs, "a cosine budget runs every epoch"
    assert [h["lr"] for h in alone[0]["history"]] == [RECIPE.lr_at(e) for e in range(RECIPE.epochs)]


@pytest.mark.slow  # trains 4 smoke runs on the PyTorch loop
def test_the_pytorch_loop_too(smoke_dataset, tmp_path):
    with native.disabled():
        alone = _records(smoke_dataset, [SMOKE], tmp_path, "alone")[0]
        three = _records(smoke_dataset, [OTHERS[0], SMOKE, OTHERS[1]], tmp_path, "three")
    assert three[1] == alone


def test_runs_of_another_shape_do_not_stack(smoke_dataset):
    with pytest.raises(ValueError, match="one shape"):
        train.train_runs([(smoke_dataset, SMOKE), (smoke_dataset, dataclasses.replace(SMOKE, hidden=32))])


@pytest.mark.slow  # trains 4 smoke runs of nn.LSTM
def test_nn_lstm_trains_through_the_one_loop_and_stacks_too(smoke_dataset, tmp_path):
    """nn.LSTM has no loop of its own: it steps member by member inside the stack, and is its own run there."""
    base, other = (dataclasses.replace(c, cell="torch-lstm") for c in (SMOKE, OTHERS[0]))
    alone = _records(smoke_dataset, [base], tmp_path, "alone")[0]
    three = _records(smoke_dataset, [other, base, dataclasses.replace(other, seed=9)], tmp_path, "three")
    assert three[1] == alone
    assert alone["history"][0]["train_loss"] != three[0]["history"][0]["train_loss"], "each member its own run"


def test_the_scheduler_stacks_runs_of_one_shape_longest_first(smoke_dataset):
    long = dataclasses.replace(SMOKE, length=2.0)
    jobs = [(smoke_dataset, c, True) for c in (SMOKE, long, dataclasses.replace(SMOKE, seed=1),
                                               dataclasses.replace(SMOKE, cell="torch-lstm"),
                                               dataclasses.replace(long, seed=1), dataclasses.replace(SMOKE, seed=2))]
    units = schedule.stacks(jobs, range(len(jobs)), size=2)
    assert units[0] == [1, 4], "the longest input first, its two runs together"
    assert sorted(map(sorted, units[1:])) == [[0, 2], [3], [5]], "at most two a stack, one shape each"
    alone = schedule.stacks(jobs, range(len(jobs)), size=1)
    assert alone[:2] == [[1], [4]] and sorted(alone[2:]) == [[0], [2], [3], [5]]
    assert schedule.stack_size("cpu") == 1 and schedule.stack_size(torch.device("cuda")) > 1


def test_a_planned_build_stops_a_chapter_at_runs_not_trained_yet(smoke_dataset, tmp_path, monkeypatch):
    """In a build that trains every chapter's runs together, asking for runs not trained writes them down and
    stops; runs that are trained pass; outside such a build, asking does nothing."""
    data = tmp_path / "data"
    ds = dataclasses.replace(smoke_dataset, path=tmp_path / "smoke.npz")
    from study.simulate import data as data_files

    data_files.save(ds, ds.path)
    jobs = [(ds, SMOKE, True), (ds, dataclasses.replace(SMOKE, seed=1), False)]
    schedule.ask(jobs, data)  # not planning: nothing happens
    pending = tmp_path / "pending.jsonl"
    monkeypatch.setenv(ticket.ENV, str(ticket.Ticket(pending=str(pending)).write(tmp_path / "ticket.json")))
    with pytest.raises(schedule.Pending, match="2 runs are not trained yet"):
        schedule.ask(jobs, data)
    with pytest.raises(schedule.Pending):
        schedule.ask(jobs[:1], data)  # asked twice: listed once
    asked = schedule.pending(pending)
    assert [(c, t) for _, c, t in asked] == [(c, t) for _, c, t in jobs]
    fake = {"key": records.run_key(ds, SMOKE, True), "config": dataclasses.asdict(SMOKE)}
    records.record_path(data, fake["key"]).parent.mkdir(parents=True)
    records.record_path(data, fake["key"]).write_text(json.dumps(fake))
    schedule.ask(jobs[:1], data)  # trained now: it passes


def test_a_build_trainer_trains_each_run_once_whoever_asks(smoke_dataset, tmp_path):
    """Two chapters asking for overlapping runs: each run is submitted once, the second asker waits on the first's
    future; the records are the ones run_many makes; a cached run is not submitted at all."""
    from concurrent.futures import wait

    from study.core.errors import StudyError
    from study.simulate import data as data_files

    data = tmp_path / "data"
    ds = dataclasses.replace(smoke_dataset, path=tmp_path / "smoke.npz")
    data_files.save(ds, ds.path)
    jobs = [(ds, SMOKE, True), (ds, dataclasses.replace(SMOKE, seed=1), False)]
    keys = {records.run_key(d, c, t) for d, c, t in jobs}
    with schedule.Trainer(data, workers=1) as trainer:
        first = trainer.submit(jobs)
        again = trainer.submit([jobs[1], jobs[1]])
        assert len(first) == 2 and again == [trainer.futures[records.run_key(*jobs[1])]]
        wait(first)
        assert trainer.trained() == keys
    made = [records.cached(d, c, data, t) for d, c, t in jobs]
    assert all(made) and _strip(made) == _strip(schedule.run_many(jobs, tmp_path / "alone", workers=1))
    with schedule.Trainer(data, workers=1) as trainer:
        assert trainer.submit(jobs) == [] and not trainer.futures, "cached runs are not trained again"
    with pytest.raises(StudyError, match="outside its 'with' block"):
        trainer.submit(jobs)


def _strip(recs: list) -> list:
    return [{k: v for k, v in r.items() if k not in ("train_seconds", "cpu_seconds")} for r in recs]
