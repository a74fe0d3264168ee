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
    from study.experiments.runtable import Run, Runs
    from study.experiments.stats import Summary
    from study.learn.config import TrainConfig
    from study.learn.metrics import Interval

    summary = [Summary({"dims": d, "length": L}, 2, 0.7, 0.0, 0.7, 0.7, 1, 0, 0, Interval(0.7, 0.65, 0.75, "x"))
               for d in ("xyz", "z") for L in (1.0, 2.0)]
    rows = Runs(Run(TrainConfig(dims=d, length=L), 0.7, 0.4, 3, 1, 1.0, a < 0.55, accuracy=a)
                for d in ("xyz", "z") for L in (1.0, 2.0) for a in (0.5, 0.72))
    fig = figures.accuracy_vs_length(summary, rows)
    assert [ax.get_title() for ax in fig.axes] == ["X, Y, Z", "Z only"]
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert "failed to train (2 runs)" in labels
    plt.close(fig)
