"""scripts/compare_builds.py pairs the numbers of two builds whatever their results format and still catches a
number that moved (or a verdict that changed) after the second format renamed the motion chapter's learners."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import scripts_toys
from study.book import results
from study.learn.config import TrainConfig
from study.learn.metrics import Interval
from study.report import reported, verdicts


def _script():
    return scripts_toys.script("scripts/compare_builds.py")


def _old_build(root: Path, value: float = 0.7) -> None:
    """A build of the first results format, under the old learner names."""
    (root / "_build").mkdir(parents=True)
    (root / "data" / "runs").mkdir(parents=True)
    entries = [
        {"name": "motion.lstm_positions.air_on.exact", "value": value, "lo": 0.68, "hi": 0.72, "method": "bootstrap",
         "chapter": "motion", "what": "peephole LSTM, positions", "unit": "fraction", "paper": None, "verdict": None,
         "source": {"seeds": [0, 1, 2]}, "decision": None},
        {"name": "table1.verdict", "value": float("nan"), "lo": float("nan"), "hi": float("nan"), "method": "verdict",
         "chapter": "table1", "what": "Table 1", "unit": "verdict", "paper": None, "verdict": "qualitative",
         "source": {}, "decision": {"rule": "qualitative", "criterion": "by eye"}},
    ]
    (root / "_build" / "results.json").write_text(json.dumps({"format": "study.results/1", "numbers": entries}))


def _new_build(root: Path, value: float = 0.7, verdict: verdicts.Decision | None = None) -> None:
    (root / "_build").mkdir(parents=True)
    (root / "data" / "runs").mkdir(parents=True)
    leaves = [("motion.peephole_positions.air_on.exact",
               reported.number(Interval(value, 0.68, 0.72, "bootstrap"), "peephole LSTM, positions", seeds=[0, 1, 2])),
              ("table1.verdict", reported.Verdict(verdict or verdicts.qualitative("by eye"), "Table 1"))]
    (root / "_build" / "results.json").write_text(results.dumps(leaves, preset="smoke"))


def test_the_same_numbers_across_the_formats_compare_equal(tmp_path):
    _old_build(tmp_path / "a")
    _new_build(tmp_path / "b")
    assert _script().main([str(tmp_path / "a"), str(tmp_path / "b")]) == 0


def test_a_moved_number_or_a_changed_verdict_is_caught(tmp_path, capsys):
    _old_build(tmp_path / "a")
    _new_build(tmp_path / "b", value=0.71)
    assert _script().main([str(tmp_path / "a"), str(tmp_path / "b")]) == 1
    assert "differs: motion.peephole_positions.air_on.exact" in capsys.readouterr().out
    _new_build(tmp_path / "c", verdict=verdicts.not_comparable("another kind"))
    assert _script().main([str(tmp_path / "a"), str(tmp_path / "c")]) == 1
    assert "differs: table1.verdict" in capsys.readouterr().out


def test_a_data_sets_key_in_a_source_is_not_compared_but_any_other_source_field_is(tmp_path):
    """A data set's key hashes the simulation's code, which a refactor moves (the engine chapter names it ``data``,
    others ``data_key``); the seeds a number was computed from are what it is."""
    def build(root: Path, **source) -> None:
        (root / "_build").mkdir(parents=True)
        (root / "data" / "runs").mkdir(parents=True)
        leaf = reported.number(Interval(0.7, 0.68, 0.72, "bootstrap"), "mass only", **source)
        (root / "_build" / "results.json").write_text(results.dumps([("engine.mass_only.bullet.accuracy", leaf)],
                                                                     preset="smoke"))
    build(tmp_path / "a", data="7471c58c8cd35bbc", data_key="c53cc2fa453ad5a2", seeds=[0, 1])
    build(tmp_path / "b", data="74bece103e0c5818", data_key="89c6d7290de8675c", seeds=[0, 1])
    build(tmp_path / "c", data="74bece103e0c5818", seeds=[0, 2])
    assert _script().main([str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    assert _script().main([str(tmp_path / "a"), str(tmp_path / "c")]) == 1


def test_builds_whose_caches_live_elsewhere_are_compared_run_by_run(tmp_path, capsys):
    """``--data A B``: the cache folders of builds made with ``study book --data-dir``."""
    _new_build(tmp_path / "a")
    _new_build(tmp_path / "b")
    (tmp_path / "cache-a" / "runs").mkdir(parents=True)
    (tmp_path / "cache-b" / "runs").mkdir(parents=True)
    record = {"key": "k1", "data_key": "d", "config": dataclasses.asdict(TrainConfig()), "test": None,
              "val_accuracy": 0.9}
    (tmp_path / "cache-a" / "runs" / "k1.json").write_text(json.dumps(record))
    args = [str(tmp_path / "a"), str(tmp_path / "b"), "--data", str(tmp_path / "cache-a"), str(tmp_path / "cache-b")]
    assert _script().main(args) == 1, "a run in one cache and not the other"
    assert "1 differ or have no counterpart" in capsys.readouterr().err
    (tmp_path / "cache-b" / "runs" / "k2.json").write_text(json.dumps({**record, "key": "k2"}))
    assert _script().main(args) == 0, "the same run under another key"


def test_a_run_from_before_the_epoch_budget_was_renamed_pairs_with_the_same_run_after(tmp_path, capsys):
    """Model format 6 renamed the config's ``max_epochs`` to ``epochs``: the same run, recorded before and after,
    is the same run; a changed budget still is not."""
    _new_build(tmp_path / "a")
    _new_build(tmp_path / "b")
    cfg = dataclasses.asdict(TrainConfig(epochs=40))
    old_cfg = {("max_epochs" if k == "epochs" else k): v for k, v in cfg.items()}
    for cache, key, config in (("cache-a", "k1", old_cfg), ("cache-b", "k2", cfg)):
        (tmp_path / cache / "runs").mkdir(parents=True)
        record = {"key": key, "data_key": "d", "config": config, "test": None, "val_accuracy": 0.9}
        (tmp_path / cache / "runs" / f"{key}.json").write_text(json.dumps(record))
    args = [str(tmp_path / "a"), str(tmp_path / "b"), "--data", str(tmp_path / "cache-a"), str(tmp_path / "cache-b")]
    assert _script().main(args) == 0
    other = {**cfg, "epochs": 41}
    (tmp_path / "cache-b" / "runs" / "k2.json").write_text(json.dumps({"key": "k2", "data_key": "d", "config": other,
                                                                        "test": None, "val_accuracy": 0.9}))
    assert _script().main(args) == 1
