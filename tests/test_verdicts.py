"""The book's one verdict rule (study.report.verdicts): a number against the paper's, a claimed order, the
kinds without a number, combining, and deciding a stored decision again at any margin."""

from __future__ import annotations

import json

import pytest

from study.core.errors import ConfigError
from study.learn.metrics import Interval
from study.report import verdicts


def test_a_paper_number_is_reproduced_inside_the_margin_and_differs_wholly_outside():
    m = verdicts.margin(0.81)  # 3 points + 1.96 sqrt(0.81 0.19 / 1000) = 3 + 2.43 points
    assert m == pytest.approx(0.03 + 1.96 * (0.81 * 0.19 / 1000) ** 0.5) and m == pytest.approx(0.0543, abs=1e-4)
    assert verdicts.margin(1.0) == verdicts.DELTA  # no sampling error at 100 %
    inside = verdicts.number(0.81, Interval(0.80, 0.78, 0.82, "x"))
    assert inside.verdict == "reproduced"
    assert inside.inputs == {"rule": "number", "paper": 0.81, "lo": 0.78, "hi": 0.82, "delta": 0.03, "n_paper": 1000}
    assert verdicts.number(0.81, Interval(0.90, 0.87, 0.93, "x")).verdict == "differs"  # wholly above p + M
    assert verdicts.number(0.81, Interval(0.70, 0.67, 0.74, "x")).verdict == "differs"  # wholly below p - M
    edge = verdicts.number(0.81, Interval(0.86, 0.84, 0.88, "x"))  # straddles p + M = 0.8643
    assert edge.verdict == "inconclusive"
    assert verdicts.number(0.81, Interval(0.81, 0.70, 0.92, "x")).verdict == "inconclusive"  # wider than the margin
    twenty = verdicts.number(0.81, Interval(0.80, 0.78, 0.82, "x"), verdicts.Margin(delta=0.0, n_paper=20))
    assert twenty.inputs["n_paper"] == 20 and twenty.inputs["delta"] == 0.0
    with pytest.raises(ConfigError, match="fraction"):
        verdicts.number(81, Interval(0.80, 0.78, 0.82, "x"))
    with pytest.raises(ConfigError, match="finite"):
        verdicts.number(0.81, Interval(float("nan"), float("nan"), float("nan"), "x"))
    with pytest.raises(ConfigError, match="Margin.delta"):
        verdicts.Margin(delta=-0.01)
    with pytest.raises(ConfigError, match="n_paper"):
        verdicts.Margin(n_paper=0)


def test_a_claimed_order_against_the_interval_of_the_difference():
    d = lambda lo, hi: Interval((lo + hi) / 2, lo, hi, "d")  # noqa: E731
    assert verdicts.order(d(0.01, 0.05), +1).verdict == "reproduced"
    assert verdicts.order(d(0.005, 0.02), +1).verdict == "reproduced"  # the order holds, if by little
    assert verdicts.order(d(-0.08, -0.04), +1).verdict == "differs"  # the other order
    assert verdicts.order(d(-0.01, 0.02), +1).verdict == "differs"  # wholly inside [-3, 3] points: no difference
    assert verdicts.order(d(-0.01, 0.05), +1).verdict == "inconclusive"  # straddles 0, reaches past delta
    assert verdicts.order(d(-0.05, -0.01), -1).verdict == "reproduced"  # A falls below B, as claimed
    assert verdicts.order(d(0.04, 0.08), -1).verdict == "differs"
    assert verdicts.order(d(-0.05, 0.01), -1).verdict == "inconclusive"
    assert verdicts.order(d(0.01, 0.05), +1).inputs == {"rule": "order", "sign": 1, "lo": 0.01, "hi": 0.05,
                                                        "delta": 0.03, "in_points": True}
    with pytest.raises(ConfigError, match="sign"):
        verdicts.order(d(0.01, 0.05), 2)


def test_an_order_of_counts_or_seconds_takes_no_margin_in_points():
    """A difference of bounces or seconds is judged on the side of 0 alone, at the book's δ and at any other."""
    d = lambda lo, hi: Interval((lo + hi) / 2, lo, hi, "d")  # noqa: E731
    tiny = verdicts.order(d(0.001, 0.02), +1, in_points=False)  # 0.001 to 0.02 s: inside ±δ, yet above 0
    assert tiny.verdict == "reproduced" and tiny.inputs["delta"] == 0.0 and tiny.inputs["in_points"] is False
    near_zero = verdicts.order(d(-0.01, 0.02), +1, in_points=False)
    assert near_zero.verdict == "inconclusive"  # in points it would be "differs": wholly inside ±3 points
    assert verdicts.order(d(-0.01, 0.02), +1).verdict == "differs"
    for k in (0.015, 0.06, 0.5):  # the summary's δ/2 and 2δ, and more, leave it alone
        assert verdicts.decide(near_zero.inputs, delta=k) == "inconclusive"
        assert verdicts.decide(tiny.inputs, delta=k) == "reproduced"
    assert verdicts.decide(verdicts.order(d(-0.01, 0.02), +1).inputs, delta=0.005) == "inconclusive"
    old = {"rule": "order", "sign": 1, "lo": -0.01, "hi": 0.02, "delta": 0.03}  # stored before the field existed
    assert verdicts.decide(old) == "differs" and verdicts.decide(old, delta=0.005) == "inconclusive"


def test_qualitative_and_not_comparable_rows_and_combining_verdicts():
    nc = verdicts.not_comparable("the paper tests on real video of heavy objects; none is public")
    q = verdicts.qualitative("both classes' heights fall and bounce as in the paper's Figure 3")
    assert nc.verdict == "not comparable" and nc.inputs["reason"].startswith("the paper tests")
    assert q.verdict == "qualitative" and q.inputs == {"rule": "qualitative", "criterion": q.inputs["criterion"]}
    assert verdicts.decide(nc.inputs) == "not comparable" and verdicts.decide(q.inputs, delta=0.5) == "qualitative"
    with pytest.raises(ConfigError, match="reason"):
        verdicts.not_comparable("")
    c = verdicts.combine
    assert c(["reproduced", "reproduced"]) == "reproduced" and c(["differs", "differs"]) == "differs"
    assert c(["reproduced", "differs"]) == c(["reproduced", "inconclusive"]) == c(["differs", "mixed"]) == "mixed"
    assert c(["inconclusive", "inconclusive"]) == "inconclusive"
    assert c(["reproduced", "qualitative", "not comparable"]) == "reproduced"  # set aside when numbers exist
    assert c(["qualitative", "not comparable"]) == "qualitative" and c(["not comparable"]) == "not comparable"
    with pytest.raises(ConfigError):
        c(["maybe"])
    with pytest.raises(ConfigError):
        c([])
    yes = verdicts.number(0.81, Interval(0.80, 0.78, 0.82, "x"))
    no = verdicts.number(0.78, Interval(0.70, 0.67, 0.72, "x"))
    both = verdicts.combined([yes, no, nc])
    assert both.verdict == "mixed" and both.inputs == {"rule": "combined", "parts": [yes.inputs, no.inputs, nc.inputs]}
    assert verdicts.combined([yes, q]).verdict == "reproduced"
    with pytest.raises(ConfigError, match="Decision"):
        verdicts.combined(["reproduced"])
    assert isinstance(both, verdicts.Combined) and isinstance(yes, verdicts.NumberDecision)


def test_every_verdict_is_decided_again_from_its_inputs_and_at_another_margin():
    iv = lambda lo, hi: Interval((lo + hi) / 2, lo, hi, "x")  # noqa: E731
    decisions = [verdicts.number(0.81, iv(0.78, 0.82)), verdicts.number(0.81, iv(0.87, 0.93)),
                 verdicts.number(0.81, iv(0.84, 0.88)), verdicts.order(iv(0.01, 0.05), 1),
                 verdicts.order(iv(-0.01, 0.02), 1), verdicts.order(iv(-0.01, 0.05), -1),
                 verdicts.not_comparable("different in kind"), verdicts.qualitative("by eye")]
    decisions.append(verdicts.combined(decisions[:3]))
    for d in decisions:
        assert verdicts.decide(d.inputs) == d.verdict
        assert verdicts.decide(json.loads(json.dumps(d.inputs))) == d.verdict  # as the results file stores them
    # borderline: [0.84, 0.865] straddles 0.81 + M (0.8643) at delta = 3 points; inside it at 6, outside at 1.5
    border = verdicts.number(0.81, iv(0.84, 0.865))
    assert border.verdict == "inconclusive"
    assert verdicts.decide(border.inputs, delta=2 * verdicts.DELTA) == "reproduced"
    assert verdicts.decide(verdicts.number(0.81, iv(0.85, 0.87)).inputs, delta=verdicts.DELTA / 2) == "differs"
    no_diff = verdicts.order(iv(-0.02, 0.025), 1)  # inside [-3, 3] points: no difference
    assert no_diff.verdict == "differs" and verdicts.decide(no_diff.inputs, delta=verdicts.DELTA / 2) == "inconclusive"
    assert verdicts.decide(decisions[-1].inputs, delta=2 * verdicts.DELTA) == "mixed"
    with pytest.raises(ConfigError, match="rule"):
        verdicts.decide({"rule": "by hand", "verdict": "reproduced"})
    with pytest.raises(ConfigError, match="malformed"):
        verdicts.decide({"rule": "number", "paper": 0.81})
    assert verdicts.from_inputs(border.inputs) == border  # the stored form reads back as the same rule
    with pytest.raises(AttributeError):
        border.verdict = "reproduced"  # a verdict is decided from its inputs, never set


