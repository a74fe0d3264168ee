"""The summary page: every table and figure of the paper against ours, read from the results file as the chapters'
own typed numbers.

:func:`compute` reads ``_build/results.json`` into each chapter's ``Numbers`` tree (:class:`Chapters`; a number
the page needs that is missing stops the build with an error naming its chapter) and builds the page's rows
(:data:`ROWS`: the paper's figure or table, what it says, ours, and the number or verdict that carries the verdict),
the verdicts at half and twice the margin, Table 1's spread, Figure 4's 2 x 2, the motion table's best learners,
and what the study adds. No name is built from strings here: every number is a field of a chapter's type.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from study.book import results
from study.experiments import (baselines, cues, decide, engines, length, motion, paper, realworld, table1, throws,
                               verdicts)
from study.experiments.reported import Leaf, Number, Reported, Verdict
from study.experiments.text import Bullets, Table, fmt


@dataclass(frozen=True)
class Chapters:
    """Every chapter's numbers, as its own type reads them back from the results file."""

    data: throws.Numbers
    table1: table1.Numbers
    cues: cues.Numbers
    motion: motion.Numbers
    engine: engines.Numbers
    length: length.Numbers
    realworld: realworld.Numbers
    decision: decide.Numbers
    baselines: baselines.Numbers

    @classmethod
    def read(cls, leaves: dict[str, Leaf]) -> Chapters:
        """Each chapter's tree from ``leaves`` (``study.book.results.load``); ``MissingResult`` names the chapter of
        a number that is not there."""
        return cls(throws.Numbers.read(leaves), table1.Numbers.read(leaves), cues.Numbers.read(leaves),
                   motion.Numbers.read(leaves), engines.Numbers.read(leaves), length.Numbers.read(leaves),
                   realworld.Numbers.read(leaves), decide.Numbers.read(leaves), baselines.Numbers.read(leaves))


@dataclass(frozen=True)
class RowSpec:
    """One row of the page, as functions of the chapters' numbers."""

    paper: str
    """The paper's figure, table or section."""
    claim: str
    """What the paper says there."""
    ours: Callable[[Chapters], str]
    """What we compare, with our numbers."""
    decided: Callable[[Chapters], Number | Verdict]
    """The number or verdict that carries the row's verdict."""
    chapter: str
    """The chapter it comes from."""


def _table1(c: Chapters, d: str) -> str:
    row = c.table1.rows[d]  # type: ignore[index]
    return f"the run validation picks: {fmt(row.paper_way)}; mean of seeds {fmt(row.mean)}"


ROWS: tuple[RowSpec, ...] = (
    RowSpec("Figure 1", "frames of a light and a heavy object on a road",
            lambda c: "rendered throws of both classes; real clips of tennis balls only",
            lambda c: c.realworld.figure1, "realworld"),
    RowSpec("Figure 2", "a trajectory: key-framed launch, then physics", lambda c: "the MuJoCo launch and record",
            lambda c: c.data.figure2, "data"),
    RowSpec("Figure 3", "light objects bounce more and stop later",
            lambda c: f"bounces, light minus heavy: {fmt(c.data.figure3.bounces)}; time to rest: "
                      f"{fmt(c.data.figure3.time_to_rest)}", lambda c: c.data.figure3.verdict, "data"),
    RowSpec("Table 1, X, Y, Z", f"{paper.TABLE1['xyz']:.0%} (best run)".replace("%", " %"),
            lambda c: _table1(c, "xyz"), lambda c: c.table1.rows["xyz"].paper_way, "table1"),
    RowSpec("Table 1, Z only", f"{paper.TABLE1['z']:.0%} (best run)".replace("%", " %"),
            lambda c: _table1(c, "z"), lambda c: c.table1.rows["z"].paper_way, "table1"),
    RowSpec("Table 1, claim", "X, Y, Z does better than Z", lambda c: f"{fmt(c.table1.xyz_minus_z)} (difference)",
            lambda c: c.table1.xyz_minus_z, "table1"),
    RowSpec("Table 1 in Bullet, X, Y, Z", f"{paper.TABLE1['xyz']:.0%} (the paper's engine)".replace("%", " %"),
            lambda c: fmt(c.engine.table1["xyz"].paper_way), lambda c: c.engine.table1["xyz"].paper_way, "engine"),
    RowSpec("Table 1 in Bullet, Z only", f"{paper.TABLE1['z']:.0%} (the paper's engine)".replace("%", " %"),
            lambda c: fmt(c.engine.table1["z"].paper_way), lambda c: c.engine.table1["z"].paper_way, "engine"),
    RowSpec("Section 2.1, claim", "no simple rule separates the classes; a more involved classifier is needed",
            lambda c: "a learned classifier against the best one-feature rule, with the air and without it",
            lambda c: c.baselines.more_involved_required, "baselines"),
    RowSpec("Figure 4", "accuracy falls for long inputs",
            lambda c: f"the longest input minus the best length: Z {fmt(c.length.drop['z'])}",
            lambda c: c.length.drop_at_long_inputs, "length"),
    RowSpec("Figure 4, explanation", "vanishing or exploding gradients over long inputs",
            lambda c: "with the gradient reaching every frame, does a memory that spans the input still help? Z "
                      f"{fmt(c.length.factorial['z'].vanishing)}", lambda c: c.length.paper_explanation, "length"),
    RowSpec("Section 2.3, ball", f"{paper.REAL_WORLD['light']:.0%} of {paper.REAL_VIDEOS} golf-ball videos".replace(
            "%", " %"), lambda c: f"{fmt(c.realworld.models['table1'].rendered['light'])} of rendered light throws",
            lambda c: c.realworld.models["table1"].rendered["light"], "realworld"),
    RowSpec("Section 2.3, cube", f"{paper.REAL_WORLD['heavy']:.0%} of {paper.REAL_VIDEOS} wooden-cube videos".replace(
            "%", " %"), lambda c: f"{fmt(c.realworld.models['table1'].rendered['heavy'])} of rendered heavy throws",
            lambda c: c.realworld.models["table1"].rendered["heavy"], "realworld"),
    RowSpec("Figure 5", "tracked heights of the real videos", lambda c: "tracked heights of rendered and real videos",
            lambda c: c.realworld.figure5, "realworld"),
    RowSpec("Figure 6", "frames of the real videos, tracked", lambda c: "the track on the last frame of each video",
            lambda c: c.realworld.figure6, "realworld"),
)
"""Every table and figure of the paper, in the paper's order."""


@dataclass(frozen=True)
class Row:
    """One row of the page: the paper's, ours, and the verdict with what decided it."""

    paper: str
    claim: str
    ours: str
    decided: Number | Verdict
    chapter: str

    @property
    def decision(self) -> verdicts.Decision:
        assert self.decided.decision is not None, f"{self.paper}: no verdict"
        return self.decided.decision

    @property
    def verdict(self) -> str:
        return self.decision.verdict

    @property
    def kind(self) -> str:
        """The rule that decided it: 'number', 'order', 'not comparable', 'qualitative' or 'combined'."""
        return self.decision.kind

    @property
    def decided_by(self) -> str:
        """The rule, and for a row without a number its reason or criterion."""
        d = self.decision
        if isinstance(d, verdicts.NotComparable):
            return f"not comparable: {d.reason}"
        if isinstance(d, verdicts.Qualitative):
            return f"qualitative: {d.criterion}"
        return d.kind


@dataclass(frozen=True)
class Numbers(Reported):
    """The summary reports no number of its own: it reads the others'."""

    CHAPTER = "summary"


@dataclass(frozen=True)
class Summary:
    """Everything the summary page shows."""

    numbers: Numbers
    chapters: Chapters
    rows: tuple[Row, ...]
    preset: str
    """The preset of this copy."""
    n_numbers: int
    """Numbers and verdicts in the build's results file."""
    n_with_ci: int
    """Of them, accuracies with a 95 % interval."""

    @property
    def at_a_glance(self) -> Table:
        return Table([{"what": r.paper, "paper": r.claim, "ours": r.ours, "verdict": f"**{r.verdict}**",
                       "rule": r.decided_by, "where": f"{{doc}}`{r.chapter}`"} for r in self.rows],
                     {"what": "paper", "paper": "the paper's number or claim", "ours": "ours [95 % CI]",
                      "verdict": "verdict", "rule": "decided by", "where": "chapter"})

    @property
    def counts(self) -> str:
        """How many rows got each verdict."""
        n = {v: sum(r.verdict == v for r in self.rows) for v in verdicts.VERDICTS}
        return ", ".join(f"{k} {v}" for v, k in n.items() if k)

    @property
    def delta(self) -> str:
        return f"{100 * verdicts.MARGIN.delta:g}"

    @property
    def n_paper(self) -> int:
        return verdicts.MARGIN.n_paper

    @property
    def margin81(self) -> str:
        return f"{100 * verdicts.margin(paper.TABLE1['xyz']):.1f}"

    @property
    def margin78(self) -> str:
        return f"{100 * verdicts.margin(paper.TABLE1['z']):.1f}"

    @property
    def sensitivity(self) -> Table:
        """Each verdict at half, once and twice the margin δ."""
        rows = []
        for r in self.rows:
            at = {f"{k:g}": r.decision.at(k * verdicts.MARGIN.delta) for k in (0.5, 1.0, 2.0)}
            rows.append({"what": r.paper, **at, "moves": "yes" if len(set(at.values())) > 1 else ""})
        d = verdicts.MARGIN.delta
        return Table(rows, {"what": "paper", "0.5": f"δ = {50 * d:g} points", "1": f"δ = {100 * d:g} points",
                            "2": f"δ = {200 * d:g} points", "moves": "does the verdict move?"})

    @property
    def spread_table(self) -> Table:
        """Table 1's seeds, their t-interval, the mean over data sets and seeds, the variance between them."""
        t1 = self.chapters.table1
        rows = []
        for label, rs in (("positions (the paper's)", t1.rows), ("with velocity (beyond the paper)", t1.velocity.rows)):
            for d in table1.ORDER:
                row = rs[d]
                rows.append({"row": label, "dims": paper.DIMS_NAMES[d],
                             "seeds": ", ".join(f"{100 * a:.1f}" for a in row.mean.source.get("per_seed", [])),
                             "t": fmt(row.mean_t), "across": fmt(row.across_data), "share": fmt(row.between_share)})
        return Table(rows, {"row": "the network reads", "dims": "input", "seeds": "each seed, data set 1 (%)",
                            "t": "mean, t-interval over seeds", "across": "over data sets and seeds [hierarchical CI]",
                            "share": "variance between data sets"})

    @property
    def factorial_table(self) -> Table:
        """Figure 4's explanation one factor at a time, each cell with its failed runs counted."""
        def cell(n: Number) -> str:
            failed = n.source.get("failed")
            return fmt(n) + (f" ({failed} of {n.source.get('runs')} runs failed to train)" if failed else "")

        rows = []
        for d in table1.ORDER:
            f = self.chapters.length.factorial[d]  # type: ignore[index]
            for t, label in (("truncated", "truncated"), ("whole", "the whole input")):
                rows.append({"dims": paper.DIMS_NAMES[d], "trunc": label, "constant": cell(f.cells[t]["constant"]),
                             "chrono": cell(f.cells[t]["chrono"])})
            rows.append({"dims": paper.DIMS_NAMES[d], "trunc": "*main effect*",
                         "constant": f"whole minus truncated: {fmt(f.effect_truncation)}",
                         "chrono": f"chrono minus constant: {fmt(f.effect_chrono)}"})
        return Table(rows, {"dims": "input", "trunc": "back-propagation through", "constant": "forget gates start constant",
                            "chrono": "forget gates start chrono"})

    @property
    def motion_table(self) -> Table:
        """The motion chapter's best learner where the camera is exact and where it is the calibrated tracker."""
        m = self.chapters.motion
        rows = []
        for air in ("air_on", "air_off"):
            for view, label in (("exact", "exact"), ("calibrated", "the calibrated tracker")):
                best = m.best[air][view]  # type: ignore[index]
                text = f"{motion.NAMES[best.learner]}: {fmt(m.learners[best.learner][air][view])}"  # type: ignore[index]
                if best.tied:
                    text += f" (tied with the {motion.NAMES[best.runner_up]}: {fmt(best.lead)})"
                rows.append({"cond": f"{air.replace('_', ' ')}, {label}",
                             "paper": fmt(m.learners["peephole_positions"][air][view]),  # type: ignore[index]
                             "best": text, "ceiling": fmt(getattr(m.ceiling, air))})
        return Table(rows, {"cond": "condition (Z, 3 s)", "paper": "the paper's network", "best": "the best learner",
                            "ceiling": "exact ceiling of the priors"})

    @property
    def adds(self) -> Bullets:
        """What the study adds to the paper, each with its number."""
        c = self.chapters
        t1, m, lg, dc = c.table1, c.motion, c.length, c.decision
        items = [
            f"The exact ceiling the priors allow without air, {fmt(m.ceiling.air_off)}, and with it "
            f"{fmt(m.ceiling.air_on)}; every learner trained under each camera beside it (*What the motion allows*).",
            f"Table 1 on several data sets: the paper's statistic computed the paper's way (the run validation picks) "
            f"and the share of variance between data sets, X, Y, Z {fmt(t1.rows['xyz'].between_share)}, Z "
            f"{fmt(t1.rows['z'].between_share)}.",
            f"The paper's network fed its velocity: Z {fmt(t1.velocity.rows['z'].mean)} against "
            f"{fmt(t1.rows['z'].mean)} on positions (*Table 1*).",
            f"The shortcut in the simulated data: one threshold on the first fall's acceleration (air drag) scores "
            f"{fmt(c.cues.drag_rule.exact)} on exact positions (*What the network sees*).",
            f"What a camera delivers: the tracker's error measured on rendered video, {fmt(c.cues.tracker.noise_m)}.",
            f"Figure 4's explanation one factor at a time: whole-input back-propagation minus truncation, Z "
            f"{fmt(lg.factorial['z'].effect_truncation)}; chrono minus a constant forget start, Z "
            f"{fmt(lg.factorial['z'].effect_chrono)} (*Accuracy against input length*).",
        ]
        exact, observed = dc.conditions["exact"], dc.clear["observed"]  # type: ignore[index]
        if exact.miss is not None and exact.false_alarm is not None and observed.share_by_end is not None:
            items.append(f"A car's decision at a certified {fmt(exact.miss)} test miss rate (target 1 %): light objects "
                         f"called heavy {fmt(exact.false_alarm)}; cleared within the input by the camera's network, "
                         f"{fmt(observed.share_by_end)} (*From accuracy to a car's decision*).")
        items.append(f"A practitioner's baseline: MiniRocket {fmt(c.baselines.accuracy['minirocket']['z']['exact'])} "
                     "on Z, exact positions.")
        items.append(f"Every accuracy with a 95 % interval: {self.n_with_ci} of the {self.n_numbers} numbers in this "
                     "build's results file.")
        return Bullets(items)


def compute(results_file: str | Path, preset: str) -> Summary:
    """The summary of the build whose results file is ``results_file``."""
    leaves = results.load(results_file)
    chapters = Chapters.read(leaves)
    rows = tuple(Row(s.paper, s.claim, s.ours(chapters), s.decided(chapters), s.chapter) for s in ROWS)
    with_ci = sum(1 for n in leaves.values() if isinstance(n, Number) and n.unit == "fraction" and n.lo != n.hi)
    return Summary(Numbers(), chapters, rows, preset, len(leaves), with_ci)
