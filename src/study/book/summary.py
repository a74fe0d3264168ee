"""The summary page: every table and figure of the paper against ours, read from the results file as the chapters'
own typed numbers.

:func:`compute` reads ``_build/results.json`` into each chapter's ``Numbers`` tree (:class:`Chapters`; a number
the page needs that is missing stops the build with an error naming its chapter) and builds the page's rows
(:data:`ROWS`: the paper's figure or table, what it says, ours, and the number or verdict that carries the verdict),
the verdicts at half and twice the margin, Table 1's spread, Figure 4's 2 x 2, the motion table's best learners,
and what the study adds. No name is built from strings here: every number is a field of a chapter's type.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from study.book import results
from study.core.errors import StudyError
from study.methods import camera, learners
from study.report import (
    baselines,
    cues,
    data,
    decision,
    engine,
    length,
    motion,
    realworld,
    table1,
    usercamera,
    verdicts,
)
from study.report.reported import Leaf, Number, Reported, Verdict
from study.report.text import Bullets, Table, fmt, fmt_value, pct
from study.runs import paper
from study.see.scale import DEFAULT as SCALE_DEFAULT


@dataclass(frozen=True)
class Chapters:
    """Every chapter's numbers, as its own type reads them back from the results file."""

    data: data.Numbers
    table1: table1.Numbers
    cues: cues.Numbers
    motion: motion.Numbers
    engine: engine.Numbers
    length: length.Numbers
    realworld: realworld.Numbers
    usercamera: usercamera.Numbers
    decision: decision.Numbers
    baselines: baselines.Numbers

    @classmethod
    def read(cls, leaves: dict[str, Leaf]) -> Chapters:
        """Each chapter's tree from ``leaves`` (``study.book.results.load``); ``MissingResult`` names the chapter of
        a number that is not there."""
        return cls(data.Numbers.read(leaves), table1.Numbers.read(leaves), cues.Numbers.read(leaves),
                   motion.Numbers.read(leaves), engine.Numbers.read(leaves), length.Numbers.read(leaves),
                   realworld.Numbers.read(leaves), usercamera.Numbers.read(leaves), decision.Numbers.read(leaves),
                   baselines.Numbers.read(leaves))

    def unread(self, leaves: Mapping[str, Leaf]) -> list[str]:
        """The names in ``leaves`` of these chapters that no chapter's type reads back: a learner, a protocol, a
        camera family or path that an experiment wrote but the typed keys (``study.report.learners``,
        ``study.learn.protocols``, ``study.simulate.observe.CAMERA_FAMILIES``, ``study.see.paths``) do not name.
        Empty for a sound build."""
        trees = [getattr(self, f.name) for f in dataclasses.fields(self)]
        read = {name for tree in trees for name, _ in tree.entries()}
        mine = tuple(f"{tree.CHAPTER}." for tree in trees)
        return sorted(n for n in leaves if n.startswith(mine) and n not in read)


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
    parts: Callable[[Chapters], Mapping[str, Number]] | None = None
    """The numbers behind a combined verdict, each under a short label (None: ``decided`` is the one number)."""


def _table1(c: Chapters, d: str) -> str:
    return f"the run validation picks: {fmt(c.table1.rows[d].paper_way)}"  # type: ignore[index]


def _parts(numbers: Mapping[str, Number]) -> str:
    """A combined row's numbers, ``'Z only: +1.2 points [...]; X, Y, Z: ...'``."""
    return "; ".join(f"{label}: {fmt(n)}" for label, n in numbers.items())


def _by_dims(numbers: Mapping[str, Number]) -> dict[str, Number]:
    return {paper.DIMS_NAMES[d]: numbers[d] for d in table1.ORDER if d in numbers}  # type: ignore[index]


def _rule_cells(c: Chapters) -> dict[str, Number]:
    return {f"{paper.DIMS_NAMES[d]}, {cond}": n for d, cells in c.baselines.peephole_minus_rule.items()
            for cond, n in cells.items()}


def _fading(c: Chapters) -> dict[str, Number]:
    return _by_dims({d: f.vanishing for d, f in c.length.factorial.items()})


def _figure3(c: Chapters) -> dict[str, Number]:
    return {"bounces, light minus heavy": c.data.figure3.bounces, "time to rest": c.data.figure3.time_to_rest}


ROWS: tuple[RowSpec, ...] = (
    RowSpec("Figure 1", "frames of a light and a heavy object on a road",
            lambda c: "rendered throws of both classes; real clips of tennis balls only",
            lambda c: c.realworld.figure1, "realworld"),
    RowSpec("Figure 2", "a trajectory: key-framed launch, then physics", lambda c: "the MuJoCo launch and record",
            lambda c: c.data.figure2, "data"),
    RowSpec("Figure 3", "light objects bounce more and stop later",
            lambda c: _parts(_figure3(c)), lambda c: c.data.figure3.verdict, "data", _figure3),
    RowSpec("Table 1, X, Y, Z", f"{paper.TABLE1['xyz']:.0%} (best run)".replace("%", " %"),
            lambda c: _table1(c, "xyz"), lambda c: c.table1.rows["xyz"].paper_way, "table1"),
    RowSpec("Table 1, Z only", f"{paper.TABLE1['z']:.0%} (best run)".replace("%", " %"),
            lambda c: _table1(c, "z"), lambda c: c.table1.rows["z"].paper_way, "table1"),
    RowSpec("Table 1, claim", "X, Y, Z does better than Z", lambda c: f"X, Y, Z minus Z: {fmt(c.table1.xyz_minus_z)}",
            lambda c: c.table1.xyz_minus_z, "table1"),
    RowSpec("Table 1 in Bullet, X, Y, Z", f"{paper.TABLE1['xyz']:.0%} (the paper's engine)".replace("%", " %"),
            lambda c: fmt(c.engine.table1["xyz"].paper_way), lambda c: c.engine.table1["xyz"].paper_way, "engine"),
    RowSpec("Table 1 in Bullet, Z only", f"{paper.TABLE1['z']:.0%} (the paper's engine)".replace("%", " %"),
            lambda c: fmt(c.engine.table1["z"].paper_way), lambda c: c.engine.table1["z"].paper_way, "engine"),
    RowSpec("Section 2.1, claim", "no simple rule separates the classes; a more involved classifier is needed",
            lambda c: "network minus best rule: " + _parts(_rule_cells(c)),
            lambda c: c.baselines.more_involved_required, "baselines", _rule_cells),
    RowSpec("Figure 4", "accuracy falls for long inputs",
            lambda c: "longest minus best length: " + _parts(_by_dims(c.length.drop)),
            lambda c: c.length.drop_at_long_inputs, "length", lambda c: _by_dims(c.length.drop)),
    RowSpec("Figure 4, explanation", "vanishing or exploding gradients over long inputs",
            lambda c: "chrono minus constant forget start, whole gradient: " + _parts(_fading(c)),
            lambda c: c.length.paper_explanation, "length", _fading),
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
    parts: tuple[tuple[str, Number], ...] = ()
    """The numbers behind the verdict, each with a short label (``""`` for a row's one number)."""

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
        if isinstance(d, verdicts.Combined):
            return "the verdicts of its numbers combined: " + "; ".join(f"{label}: {n.verdict}" for label, n in self.parts)
        return {"number": "our interval against the paper's number ± its margin",
                "order": "our difference against 0 and ±δ"}.get(d.kind, d.kind)


def _row(spec: RowSpec, c: Chapters) -> Row:
    """A row of the page; the numbers behind a combined verdict must decide it again, else the row is wrong."""
    decided = spec.decided(c)
    parts = tuple(spec.parts(c).items()) if spec.parts else ((("", decided),) if isinstance(decided, Number) else ())
    row = Row(spec.paper, spec.claim, spec.ours(c), decided, spec.chapter, parts)
    if spec.parts and verdicts.combine([n.verdict or "not comparable" for _, n in parts]) != row.verdict:
        raise StudyError(f"summary, {spec.paper}: its numbers decide {[n.verdict for _, n in parts]}, its verdict "
                         f"is {row.verdict!r}; the row's parts are not the numbers behind its verdict")
    return row


# ---------------------------------------------------------------------------------------------
# The findings and the figures' data


def _mm(n: Number) -> str:
    """A camera's error (metres) in millimetres."""
    return f"{1000 * n.value:.1f} mm"


_BOTH = {"reproduced": "both reproduce the paper's", "differs": "both differ from the paper's",
         "inconclusive": "both inconclusive", "not comparable": "neither comparable"}


def _both(numbers: Mapping[str, Number]) -> str:
    """The verdicts of a row pair (X, Y, Z; Z), in words."""
    a, b = (numbers[d].verdict for d in table1.ORDER)
    return _BOTH.get(a or "", f"both {a}") if a == b else f"X, Y, Z {a}, Z {b}"


def unsettled_clause(unsettled: Mapping[str, int]) -> str:
    """'' or, for Table 1's rows (input -> how many of its runs validation picks had not flattened when their epoch
    budget ran out), the clause the findings add after the rows' verdicts."""
    if not any(unsettled.values()):
        return ""
    rows = " and ".join(f"{n} behind {'X, Y, Z' if d == 'xyz' else 'Z alone'}" for d, n in unsettled.items() if n)
    return (f"; of the runs validation picks, {rows} had not flattened when "
            f"{'its' if sum(unsettled.values()) == 1 else 'their'} epochs ran out")


@dataclass(frozen=True)
class Best:
    """A column's best learner and its accuracy."""

    name: str
    """Its name, in words."""
    accuracy: Number


@dataclass(frozen=True)
class Findings:
    """The numbers the page's first paragraph tells in words (:attr:`text`)."""

    verdicts: Mapping[str, int]
    """How many of the paper's rows got each verdict."""
    table1: Mapping[str, Number]
    """Table 1 as the paper computes it, ours, in MuJoCo: input -> the run validation picks."""
    bullet: Mapping[str, Number]
    """The same in Bullet, the paper's engine."""
    ceiling: Mapping[str, Number]
    """The exact ceiling of the priors: ``air_on``, ``air_off``."""
    drag_rule: Number
    """One threshold on the first fall's acceleration, exact positions, with air."""
    network: Mapping[str, Number]
    """The paper's network on Z, exact positions: ``air_on``, ``air_off``."""
    camera: Mapping[str, Best]
    """The best learner through the calibrated camera: ``air_on``, ``air_off``."""
    camera_error: Number
    """The calibrated camera's height error, metres."""
    sweep: usercamera.Sweep | None = None
    """The camera sweep: a camera nobody measured (None: not in the results file)."""
    unsettled: Mapping[str, int] = dataclasses.field(default_factory=dict)
    """Table 1's runs validation picks that had not flattened when their epoch budget ran out
    (``study.runs.failures.unsettled``): input -> how many (none for a results file from before they were counted)."""

    @classmethod
    def of(cls, c: Chapters, rows: tuple[Row, ...]) -> Findings:
        m, airs = c.motion, ("air_on", "air_off")
        best = {a: m.best[a]["calibrated"].learner for a in airs}  # type: ignore[index]
        camera = {a: Best(learners.NAMES[k], m.learners[k][a]["calibrated"]) for a, k in best.items()}  # type: ignore[index]
        return cls({v: sum(r.verdict == v for r in rows) for v in verdicts.VERDICTS},
                   {d: c.table1.rows[d].paper_way for d in table1.ORDER},  # type: ignore[index]
                   {d: c.engine.table1[d].paper_way for d in table1.ORDER},  # type: ignore[index]
                   {a: getattr(m.ceiling, a) for a in airs}, c.cues.drag_rule.exact,
                   {a: m.learners["peephole_positions"][a]["exact"] for a in airs},  # type: ignore[index]
                   camera, m.noise["calibrated"], c.usercamera.sweep,  # type: ignore[index]
                   {d: int(n.value) for d in table1.ORDER  # type: ignore[index]
                    if (n := c.table1.rows[d].unsettled_picks) is not None})

    @property
    def text(self) -> str:
        """The study's findings in plain words: what the paper found, what held, what the motion allows, what a
        camera leaves of it."""
        n, t, b = self.verdicts, self.table1, self.bullet
        held = ", ".join([f"{n['reproduced'] or 'none'} reproduced"]
                         + [f"{n[v]} {'differ' if v == 'differs' else v}" for v in ("differs", "inconclusive", "mixed")
                            if n[v]])
        held += f"; {n['qualitative']} qualitative and {n['not comparable']} not comparable"
        on, off = self.camera["air_on"], self.camera["air_off"]
        return (f"The paper trains a small recurrent network on simulated throws and reports "
                f"{pct(paper.TABLE1['xyz'], 0)} with X, Y, Z and {pct(paper.TABLE1['z'], 0)} with the height "
                f"alone (Table 1). Of its {sum(n.values())} tables, figures and claims, {held}. Our Table 1 scores "
                f"{fmt(t['xyz'])} and {fmt(t['z'])} ({_both(t)}{unsettled_clause(self.unsettled)}); in Bullet, the "
                f"paper's engine, {fmt(b['xyz'])} and {fmt(b['z'])} ({_both(b)}). What the motion allows is exact: "
                f"no classifier can beat {fmt_value(self.ceiling['air_off'].value)} without air, "
                f"{fmt_value(self.ceiling['air_on'].value)} with it, and there one threshold on the first fall's "
                f"acceleration already scores "
                f"{fmt(self.drag_rule)}; the paper's network reaches {fmt(self.network['air_on'])} with air and "
                f"{fmt(self.network['air_off'])} without. A camera leaves less: through the calibrated camera "
                f"({_mm(self.camera_error)} of height error) the best learner scores {fmt(on.accuracy)} with air "
                f"({on.name}) and {fmt(off.accuracy)} without ({off.name})." + self._user_camera)

    @property
    def _user_camera(self) -> str:
        """The camera sweep in one sentence ('' without it)."""
        if self.sweep is None:
            return ""
        everything = self.sweep.groups["all"]  # type: ignore[index]
        a, d, k = everything.paths, self.sweep.drag, SCALE_DEFAULT
        off = fmt_value(a[k].heights_mm.value, "mm") if a[k].heights_mm else "—"
        return (f" A camera nobody measured leaves less still: on {fmt_value(everything.clips.value, 'count')} clips "
                f"from random cameras, the recommended model scores {fmt(a['exact'].accuracy)} from the throws' exact "
                f"heights and {fmt(a[k].accuracy)} from what a user's video gives (heights off by {off} RMS), and the "
                f"drag rule scores {fmt(d['exact'])} on exact heights and {fmt(d[k])} on a user's.")



@dataclass(frozen=True)
class Mark:
    """One marker of the forest plot: one of our numbers that decides a verdict against the paper."""

    label: str
    """What it is, short (the row and the part)."""
    number: Number
    """Ours with its 95 % interval; its decision holds the paper's number or the claimed order."""
    verdict: str
    """Its own verdict."""

    @property
    def scale(self) -> float:
        """Factor to the axis' unit: 100 for a fraction (percent, or points for a difference), else 1."""
        return 100.0 if self.number.unit == "fraction" else 1.0

    @property
    def paper(self) -> float | None:
        """The paper's number (a fraction) for a number rule, else None."""
        d = self.number.decision
        return d.paper if isinstance(d, verdicts.NumberDecision) else None

    @property
    def margin(self) -> float:
        """The half-width around the paper's number inside which ours reproduces it; for an order, δ (0 for a
        difference that is not in accuracy points)."""
        d = self.number.decision
        if isinstance(d, verdicts.NumberDecision):
            return verdicts.margin(d.paper, verdicts.Margin(d.delta, d.n_paper))
        assert isinstance(d, verdicts.OrderDecision), self.label
        return d.delta if d.in_points else 0.0

    @property
    def sign(self) -> int:
        """The claimed side of 0 for an order (+1 or -1), 0 for a number."""
        d = self.number.decision
        return d.sign if isinstance(d, verdicts.OrderDecision) else 0


@dataclass(frozen=True)
class Forest:
    """The summary's first figure: every number of the paper that has a margin, every claimed order, and the rows
    without a marker (:func:`study.book.figures.forest`)."""

    numbers: tuple[Mark, ...]
    """Ours against a number of the paper and its margin."""
    orders: tuple[Mark, ...]
    """Differences of ours against 0 and ±δ, each in its own unit."""
    unmarked: tuple[tuple[str, str], ...]
    """(row, verdict) of the rows without a number of ours to draw: qualitative and not comparable."""

    @classmethod
    def of(cls, rows: tuple[Row, ...]) -> Forest:
        numbers: list[Mark] = []
        orders: list[Mark] = []
        unmarked: list[tuple[str, str]] = []
        for r in rows:
            drawn = False
            for label, n in r.parts:
                mark = Mark(f"{r.paper}: {label}" if label else r.paper, n, n.verdict or "")
                if isinstance(n.decision, verdicts.NumberDecision):
                    numbers.append(mark)
                elif isinstance(n.decision, verdicts.OrderDecision):
                    orders.append(mark)
                else:
                    continue
                drawn = True
            if not drawn:
                unmarked.append((r.paper, r.verdict))
        return cls(tuple(numbers), tuple(orders), tuple(unmarked))

    @property
    def units(self) -> tuple[str, ...]:
        """The orders' units, accuracy points first: one panel each."""
        seen = dict.fromkeys(m.number.unit for m in self.orders)
        return tuple(sorted(seen, key=lambda u: u != "fraction"))


@dataclass(frozen=True)
class Condition:
    """One row of the second figure: a condition the paper did not test, and the learners' accuracy in it."""

    label: str
    """The condition, in words."""
    accuracy: Mapping[str, Number]
    """Learner (``study.methods.learners.NAMES``) -> its test accuracy there."""
    best: str | None
    """The condition's best learner, None where the chapter names none."""


@dataclass(frozen=True)
class Panel:
    """One air setting of the second figure, with its exact ceiling."""

    title: str
    ceiling: Number
    """The exact ceiling of the priors."""
    conditions: tuple[Condition, ...]


@dataclass(frozen=True)
class Allows:
    """The summary's second figure: what the study adds (:func:`study.book.figures.what_the_motion_allows`)."""

    panels: tuple[Panel, ...]
    names: Mapping[str, str]
    """Learner -> its name in the legend."""

    @classmethod
    def of(cls, c: Chapters) -> Allows:
        m, shown = c.motion, ("peephole_positions", "peephole_velocity")
        panels = []
        for air, title, ceiling in (("air_on", "the study's throws, with air", m.ceiling.air_on),
                                    ("air_off", "the same throws without air", m.ceiling.air_off)):
            rows = []
            for view in camera.VIEWS:
                best = m.best[air][view].learner  # type: ignore[index]
                seen = "exact positions" if view == "exact" else f"{view} camera, {_mm(m.noise[view])} error"  # type: ignore[index]
                acc = {k: m.learners[k][air][view] for k in (*shown, best)}  # type: ignore[index]
                rows.append(Condition(f"MuJoCo, {seen}", acc, best))
            if air == "air_off":  # the engine chapter trains on the air-off throws, in both engines
                for view in ("exact", "calibrated"):
                    cross = c.engine.cross
                    acc = {k: cross[k][view]["bullet_to_bullet"] for k in shown if k in cross}  # type: ignore[index]
                    rows.append(Condition(f"Bullet, {'exact positions' if view == 'exact' else view + ' camera'}",
                                          acc, None))
            panels.append(Panel(title, ceiling, tuple(rows)))
        return cls(tuple(panels), dict(learners.NAMES))


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
    def findings(self) -> str:
        """The page's first paragraph: the study's findings in plain words, every number from the results."""
        return Findings.of(self.chapters, self.rows).text

    @property
    def forest(self) -> Forest:
        """The first figure's data (``study.book.figures.forest``)."""
        return Forest.of(self.rows)

    @property
    def allows(self) -> Allows:
        """The second figure's data (``study.book.figures.what_the_motion_allows``)."""
        return Allows.of(self.chapters)

    @property
    def at_a_glance(self) -> Table:
        """Every row of the paper: what it says (linked to the chapter), ours, the verdict; short cells."""
        return Table([{"paper": f"{{doc}}`{r.paper} <{r.chapter}>`: {r.claim}", "ours": r.ours,
                       "verdict": f"**{r.verdict}**"} for r in self.rows],
                     {"paper": "the paper says", "ours": "ours [95 % CI]", "verdict": "verdict"})

    @property
    def criteria(self) -> Table:
        """What decided each row's verdict: the rule, or the reason or criterion of a row without a number."""
        return Table([{"paper": r.paper, "rule": r.decided_by} for r in self.rows],
                     {"paper": "paper", "rule": "decided by"})

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
                text = f"{learners.NAMES[best.learner]}: {fmt(m.learners[best.learner][air][view])}"  # type: ignore[index]
                if best.tied:
                    text += f" (tied with the {learners.NAMES[best.runner_up]}: {fmt(best.lead)})"
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
        if exact.miss is not None and exact.false_alarm is not None and observed.headline is not None:
            items.append(f"A car's decision at a certified {fmt(exact.miss)} test miss rate (target 1 %; Table 1's Z "
                         f"network, its seeds as one classifier): light objects called heavy {fmt(exact.false_alarm)}; "
                         f"cleared within the input by the camera's network, {fmt(observed.headline)} (*From accuracy "
                         "to a car's decision*).")
        items.append(f"A practitioner's baseline: MiniRocket {fmt(c.baselines.accuracy['minirocket']['z']['exact'])} "
                     "on Z, exact positions.")
        items.append(f"Every accuracy with a 95 % interval: {self.n_with_ci} of the {self.n_numbers} numbers in this "
                     "build's results file.")
        return Bullets(items)


def compute(results_file: str | Path, preset: str) -> Summary:
    """The summary of the build whose results file is ``results_file``."""
    leaves = results.load(results_file)
    chapters = Chapters.read(leaves)
    rows = tuple(_row(s, chapters) for s in ROWS)
    with_ci = sum(1 for n in leaves.values() if isinstance(n, Number) and n.unit == "fraction" and n.lo != n.hi)
    return Summary(Numbers(), chapters, rows, preset, len(leaves), with_ci)
