"""The book's figure style: class colours and the colour cycle."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from study.book import figures


def test_the_class_colours_are_colour_blind_safe_and_start_the_cycle() -> None:
    assert set(figures.CLASS_COLORS.values()) <= set(figures.OKABE_ITO.values())
    assert len(set(figures.CLASS_COLORS.values())) == 2
    figures.use_style()
    cycle = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    assert [c.upper() for c in cycle[:2]] == [figures.CLASS_COLORS[c].upper() for c in ("light", "heavy")]


def test_accuracy_vs_length_draws_both_inputs_with_failed_runs_marked() -> None:
    from study.learn.config import TrainConfig
    from study.learn.metrics import Interval
    from study.runs.runtable import Run, Runs
    from study.runs.stats import Summary

    summary = [Summary({"dims": d, "length": L}, 2, 0.7, 0.0, 0.7, 0.7, 1, 0, 0, Interval(0.7, 0.65, 0.75, "x"))
               for d in ("xyz", "z") for L in (1.0, 2.0)]
    rows = Runs(Run(TrainConfig(dims=d, length=L), 0.7, 0.4, 3, 1, 1.0, a < 0.55, accuracy=a)
                for d in ("xyz", "z") for L in (1.0, 2.0) for a in (0.5, 0.72))
    fig = figures.accuracy_vs_length(summary, rows)
    assert [ax.get_title() for ax in fig.axes] == ["X, Y, Z", "Z only"]
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert "failed to train (2 runs)" in labels
    plt.close(fig)


def test_the_sample_trajectories_put_heavy_on_top_with_a_unit_on_every_axis() -> None:
    import numpy as np

    x = np.zeros((4, 5, 3))
    fig = figures.sample_trajectories(np.arange(5) / 30, x, {"heavy": [0, 1], "light": [2]})
    axes = fig.axes
    assert [ax.get_title() for ax in axes[:3]] == ["heavy: X", "heavy: Y", "heavy: Z"]
    assert all(ax.get_ylabel().endswith(", m") for ax in axes) and axes[-1].get_xlabel() == "time, s"
    assert [len(ax.lines) for ax in axes] == [2, 2, 2, 1, 1, 1], "one line per sampled throw"
    plt.close(fig)


def test_the_learners_are_drawn_against_the_camera_with_their_ceiling() -> None:
    from study.learn.metrics import Interval

    def curve(name, air):
        return np.array([0.0, 3.0]), [Interval(0.6, 0.5, 0.7, "x"), Interval(0.55 if air else 0.5, 0.45, 0.65, "x")]

    import numpy as np

    fig = figures.learners_against_camera(curve, lambda air: 1.0 if air else 0.86, ["a", "b"], {"a": "A", "b": "B"})
    on, off = fig.axes
    assert (on.get_title(), off.get_title()) == ("air on", "air off")
    assert [line.get_ydata()[0] for line in off.lines if line.get_linestyle() == "--"] == [86.0], "the ceiling, %"
    assert off.get_legend_handles_labels()[1] == ["ceiling", "A", "B"] and "mm" in on.get_xlabel()
    plt.close(fig)


def test_the_engines_agreement_is_one_histogram_per_difference_and_class() -> None:
    import numpy as np

    y = np.array([0, 0, 1, 1])
    diffs = {"bounces": np.array([0.0, 1.0, -1.0, 0.0]), "distance": np.array([0.1, 0.2, 0.0, -0.1])}
    fig = figures.engine_agreement(diffs, y, {"bounces": "bounces", "distance": "distance, m"})
    assert [ax.get_xlabel() for ax in fig.axes] == ["Bullet − MuJoCo: bounces", "Bullet − MuJoCo: distance, m"]
    assert all(len(ax.containers) == 2 for ax in fig.axes), "light and heavy"
    plt.close(fig)
