"""The summary page's data and figure, from hand-made rows: which of our numbers the forest plot draws, where,
with which verdict, and which rows it names without a marker."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import pytest

from study.book import figures, summary
from study.learn.metrics import Interval
from study.report import verdicts
from study.report.reported import Verdict, number


def _rows() -> tuple[summary.Row, ...]:
    xyz = number(Interval(0.80, 0.77, 0.83, "bootstrap"), "Table 1, X, Y, Z", paper=0.81)  # inside 81 ± 5.4
    z = number(Interval(0.60, 0.55, 0.65, "bootstrap"), "Table 1, Z", paper=0.78)  # wholly below
    gap = number(Interval(0.05, 0.01, 0.09, "paired"), "X, Y, Z minus Z", signed=True,
                 decision=verdicts.order(Interval(0.05, 0.01, 0.09, "paired"), +1))
    bounces = number(Interval(1.2, -0.2, 2.6, "bootstrap"), "bounces", unit="count", signed=True,
                     decision=verdicts.order(Interval(1.2, -0.2, 2.6, "bootstrap"), +1, in_points=False))
    rest = number(Interval(0.4, 0.1, 0.7, "bootstrap"), "time to rest", unit="s", signed=True,
                  decision=verdicts.order(Interval(0.4, 0.1, 0.7, "bootstrap"), +1, in_points=False))
    fig3 = Verdict(verdicts.combined([bounces.decision, rest.decision]), "Figure 3")
    fig2 = Verdict(verdicts.qualitative("a key-framed launch"), "Figure 2")
    ball = Verdict(verdicts.not_comparable("rendered, not filmed"), "ball")
    return (summary.Row("Table 1, X, Y, Z", "81 %", "", xyz, "table1", (("", xyz),)),
            summary.Row("Table 1, Z only", "78 %", "", z, "table1", (("", z),)),
            summary.Row("Table 1, claim", "X, Y, Z over Z", "", gap, "table1", (("", gap),)),
            summary.Row("Figure 3", "bounce more", "", fig3, "data", (("bounces", bounces), ("rest", rest))),
            summary.Row("Figure 2", "a launch", "", fig2, "data"),
            summary.Row("Section 2.3, ball", "93 %", "", ball, "realworld"))


def test_the_forest_draws_each_paper_number_and_each_order_and_names_the_rest():
    f = summary.Forest.of(_rows())
    assert [m.label for m in f.numbers] == ["Table 1, X, Y, Z", "Table 1, Z only"]
    assert [m.verdict for m in f.numbers] == ["reproduced", "differs"]
    assert f.numbers[0].paper == 0.81 and f.numbers[0].margin == pytest.approx(verdicts.margin(0.81))
    assert [m.label for m in f.orders] == ["Table 1, claim", "Figure 3: bounces", "Figure 3: rest"]
    assert f.orders[0].margin == verdicts.MARGIN.delta and f.orders[1].margin == 0.0, "no δ for a count"
    assert f.units == ("fraction", "count", "s"), "accuracy points first, one panel per unit"
    assert f.unmarked == (("Figure 2", "qualitative"), ("Section 2.3, ball", "not comparable"))
    assert f.orders[0].scale == 100.0 and f.orders[2].scale == 1.0


def test_the_forest_figure_has_a_panel_per_unit_and_the_verdict_in_colour_and_shape():
    fig = figures.forest(summary.Forest.of(_rows()))
    top, points, count, seconds, foot = fig.axes
    assert top.get_xlabel() == "test accuracy (%)" and points.get_xlabel() == "difference (accuracy points)"
    assert count.get_xlabel() == "difference (bounces, a count)" and seconds.get_xlabel() == "difference (seconds)"
    markers = [ln.get_marker() for ln in top.get_lines() if ln.get_marker() in ("o", "s", "D")]
    assert markers == [figures.VERDICT_STYLE["reproduced"][1], figures.VERDICT_STYLE["differs"][1]]
    assert len(top.patches) == 2, "a margin band around each of the paper's numbers"
    assert "Figure 2" in foot.texts[0].get_text() and "not comparable" in foot.texts[0].get_text()
    plt.close(fig)


def test_a_combined_row_whose_parts_decide_otherwise_is_refused():
    spec = summary.RowSpec("Figure 3", "bounce more", lambda c: "", lambda c: _rows()[3].decided, "data",
                           lambda c: {"bounces": _rows()[1].decided})  # a part that differs: not its parts
    with pytest.raises(summary.StudyError, match="Figure 3"):
        summary._row(spec, None)  # type: ignore[arg-type]
