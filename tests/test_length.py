"""The chapter *Accuracy against input length*: its computation on run records written into a fresh cache (nothing
trains), and its pure parts on small arrays."""

from __future__ import annotations

import dataclasses
import typing

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from fake_runs import cache_records

from study.book import figures, results
from study.chapters import length
from study.learn.config import TrainConfig
from study.learn.metrics import Interval
from study.runs import PRESETS, Runner, paper, stats
from study.runs.runtable import Run, Runs

pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")

SWEEP = {"z": {0.5: 0.5, 1.0: 1.0, 1.5: 0.5}, "xyz": {0.5: 0.6, 1.0: 0.7, 1.5: 0.8}}
"""Test accuracy of the fake sweep (Table 1's truncation, constant forget start): Z peaks at 1 s and falls at the
longest input (its 0.5 s runs fail to train, at chance); X, Y, Z rises to the end."""
WHOLE = {"z": {"constant": 1.0, "chrono": 1.0}, "xyz": {"constant": 0.5, "chrono": 1.0}}
"""The 2 x 2's cells with the whole input back-propagated (truncated cells: chrono as constant): with Z the
gradient's reach is all that matters; with X, Y, Z only the spanning memory helps (fading gradients)."""


def _score(c: TrainConfig) -> float:
    if c.truncation >= c.n_frames(30.0):  # the whole input (the smoke data are at 30 frames a second)
        return WHOLE[c.dims][c.forget_init]
    return SWEEP[c.dims][c.length]


def _val(c: TrainConfig) -> float:
    """Validation accuracy: at chance (failed to train) for Z at 0.5 s only."""
    return 0.5 if (c.dims, c.length) == ("z", 0.5) else 1.0


@pytest.fixture(scope="module")
def runner(tmp_path_factory) -> Runner:
    return Runner.open("smoke", data_dir=tmp_path_factory.mktemp("data"))


@pytest.fixture(scope="module")
def cfg(runner) -> TrainConfig:
    # Table 1's truncation on the smoke data; half the training split for validation, so that a run that trained
    # can be told from guessing (on the smoke split's 3 validation throws, none can)
    return dataclasses.replace(runner.preset.base_config(), truncation=10, val_fraction=0.5)


@pytest.fixture(scope="module")
def result(runner, cfg) -> length.Length:
    assert runner.fps == 30.0
    p = runner.preset
    cache_records(runner, paper.length_configs(cfg, p) + paper.long_memory_configs(cfg, p, runner.fps)
                  + [c for _, _, c in paper.factorial_configs(cfg, p, runner.fps)], _score, val_score=_val)
    return length.compute(runner, cfg)


def test_the_drop_is_the_longest_minus_the_best_length_and_its_verdict_follows(result):
    e = result.effects
    assert (e["z"].best_length, e["z"].last_length) == (1.0, 1.5)
    assert e["xyz"].best_length == e["xyz"].last_length == 1.5, "X, Y, Z rises to the end"
    z, xyz = result.numbers.drop["z"], result.numbers.drop["xyz"]
    assert (z.value, z.hi) == (-0.5, -0.25) and z.verdict == "reproduced"
    assert xyz.value == 0 and xyz.lo < 0 < xyz.hi and xyz.verdict == "inconclusive", \
        "the best is the longest: the seeds alone move the difference"
    assert result.numbers.drop_at_long_inputs.verdict == "mixed"
    assert result.drop_claim.startswith("Long inputs hurt with Z only:")
    assert result.drop_words == ("X, Y, Z +0.0 points [-15.6, +15.7] (inconclusive); "
                                 "Z only -50.0 points [-68.8, -25.0] (reproduced)")


def test_the_factorial_tells_the_gradients_reach_from_its_fading(result):
    f = result.numbers.factorial
    assert f["z"].cells["whole"]["chrono"].value == 1.0 and f["z"].effect_truncation.lo > 0
    assert f["z"].vanishing.verdict == "differs", "with the whole input, chrono adds nothing on Z"
    assert f["xyz"].vanishing.verdict == "reproduced" and f["xyz"].vanishing.lo > 0
    assert result.numbers.paper_explanation.verdict == "mixed"
    assert f["z"].cells["truncated"]["constant"].value == result.numbers.sweep["z"]["1.5s"].value, \
        "the truncated, constant cell is the sweep's run at the longest input"
    src = f["xyz"].cells["whole"]["constant"].source
    assert src == {"runs": 1, "failed": 0}
    words = result.control_verdict
    assert "With X, Y, Z, back-propagating through the whole input does not help, the chrono start does not" in words
    assert "the spanning memory still adds accuracy, as fading (vanishing) gradients would" in words
    assert "With Z only, back-propagating through the whole input recovers accuracy, the chrono start does not" in words
    assert len(result.control_table.rows) == 8 and result.control_table.rows[0]["dims"] == "X, Y, Z"


def test_counts_failures_and_tables(result):
    assert result.n_runs == 12 and result.n_failed == 2 and result.numbers.failed_runs.value == 2
    assert result.failed_where == "Z only at 0.5 s"
    assert result.window_why.startswith("2 of the 4 runs at 0.5 s failed to train.")
    assert (result.n_lengths, result.n_len_seeds, result.trunc, result.control_last) == (3, 2, 10, 1.5)
    assert 0 <= result.moving_last <= 100
    md = result.length_table.markdown()
    assert md.count("\n") == 4 and "(2 of 2 failed to train" in md.splitlines()[2]
    assert result.xyz_best_mean == pytest.approx(100 * result.numbers.sweep["xyz"]["1.5s"].value)


def test_every_number_keeps_its_name_and_reads_back_from_the_results_file(result, tmp_path):
    names = [name for name, _ in result.numbers.entries()]
    for d in ("xyz", "z"):
        assert {f"length.{d}.0.5s", f"length.{d}.1.5s", f"length.long_memory.{d}.1.5s", f"length.drop.{d}",
                f"length.factorial.{d}.effect_truncation", f"length.factorial.{d}.effect_chrono",
                f"length.factorial.{d}.vanishing"} <= set(names)
        for t in ("truncated", "whole"):
            assert {f"length.factorial.{d}.{t}.constant", f"length.factorial.{d}.{t}.chrono"} <= set(names)
    assert {"length.failed_runs", "length.drop_at_long_inputs", "length.paper_explanation",
            "length.window.0.5s.other_rule", "length.window.0.5s.drag_rule"} <= set(names)
    assert len(names) == 29
    f = tmp_path / "results.json"
    f.write_text(results.dumps(result.numbers.entries()))
    assert length.Numbers.read(results.load(f)) == result.numbers


def test_every_presets_lengths_have_a_name():
    keys = set(typing.get_args(length.LengthKey))
    assert {length.length_key(L) for p in PRESETS.values() for L in p.lengths + p.long_lengths} <= keys
    assert length.length_key(1.0) == "1s" and length.length_key(0.5) == "0.5s"


def _run(dims: str, L: float, accuracy: float, failed: bool = False) -> Run:
    correct = np.arange(10) < round(10 * accuracy)
    return Run(TrainConfig(dims=dims, length=L), 0.7, 0.4, 3, 1, 1.0, failed, accuracy=accuracy, correct=correct)


def test_long_input_effect_groups_runs_by_length():
    runs = Runs([_run("z", 1.0, 0.7), _run("z", 2.0, 0.8), _run("z", 4.0, 0.7)])
    e = stats.long_input_effect(stats.summarise(runs, ("dims", "length")), "z")
    assert (e.best_length, e.last_length, e.best_mean) == (2.0, 4.0, 0.8)
    assert e.drop == pytest.approx(0.1) and not e.hurts, "ten throws: the intervals overlap"


def test_window_why_tells_nothing_to_learn_from_a_failure_to_learn():
    runs = Runs([_run("z", 0.5, 0.5, failed=True), _run("z", 0.5, 0.9)])
    empty = {"length": 0.5, "other": Interval(0.5, 0.4, 0.55, ""), "drag": Interval(0.9, 0.85, 0.95, "")}
    assert "not yet in the window" in length.window_why(empty, runs) and "no rule on them does better than 55 %" \
        in length.window_why(empty, runs)
    full = empty | {"other": Interval(0.8, 0.7, 0.9, "")}
    assert length.window_why(full, runs) == ("1 of the 2 runs at 0.5 s failed to train. The window holds cues a rule "
                                             "can use, so these runs failed to learn, not to find information.")
    assert length.window_why(full, Runs([_run("z", 0.5, 0.9)])) == "No run at 0.5 s failed to train."


def test_the_figure_draws_both_inputs_with_failed_runs_marked(result):
    s = result.sweep
    fig = figures.accuracy_vs_length(s.summary, s.runs, s.long_summary)
    assert [ax.get_title() for ax in fig.axes] == ["X, Y, Z", "Z only"]
    labels = [ax.get_legend_handles_labels()[1] for ax in fig.axes]
    assert "failed to train (0 runs)" in labels[0] and "memory that spans the input (chrono, full BPTT)" in labels[0]
    line = fig.axes[1].get_lines()[0]
    assert list(line.get_xdata()) == [0.5, 1.0, 1.5] and list(line.get_ydata()) == [50.0, 100.0, 50.0]
    plt.close(fig)


def test_the_2x2_says_which_cells_cannot_train_and_why_in_numbers():
    cfg = TrainConfig(dims="z", length=6.0, truncation=90, forget_bias=1.0)

    def runs(failed: int, n: int = 3) -> Runs:
        return Runs(Run(cfg, 0.5, 0.69, 30, 0, 1.0, i < failed) for i in range(n))

    trained = {(t, f): runs(0) for t in ("truncated", "whole") for f in ("constant", "chrono")}
    assert length.untrainable_words({"z": length.Cells(trained)}, cfg, 30.0, 6.0, 2.5) == \
        "Every run of the 2 × 2 at 6 s trained."
    cells = {"z": length.Cells({**trained, ("whole", "constant"): runs(3), ("truncated", "chrono"): runs(1)})}
    words = length.untrainable_words(cells, cfg, 30.0, 6.0, 2.5)
    assert "Z only, whole input, constant start: 3 of 3" in words and "Z only, truncated, chrono start: 1 of 3" in words
    assert "only the last 90 frames, where only 2.5 % of the test objects still move" in words
    assert "keep 0.73 of the state per frame" in words and "150 frames before the answer" in words
    assert f"{length.memory_left(1.0, 150):.0e}" in words and length.memory_left(1.0, 150) < 1e-19
