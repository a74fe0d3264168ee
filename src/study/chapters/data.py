"""The chapter *The data*: the throws the study learns from, what they look like, and the physics behind them.

:func:`compute` takes one simulated data set and returns :class:`DataChapter`, built step by step:

1. the class and launch priors with their sources (:func:`prior_table`);
2. the paper's Figure 2, how a trajectory is made: frames and the height of one light throw (:func:`filmstrip`);
3. the paper's Figure 3: sample throws of each class (:func:`sample_throws`) and its two claims as statistics,
   light minus heavy in bounces and in time to rest, with their verdicts (:func:`figure3`);
4. the data's statistics per class (:func:`stats_table`);
5. whether one simple rule separates the classes: the best threshold on each one-number summary, chosen on the
   training split and scored on the test split, and the best of them by training accuracy (:func:`simple_rules`);
6. every physics check the chapter shows, each a typed result: free flight (:func:`free_flight`), the
   restitution's calibration, drops and timestep convergence (:func:`restitution`), penetration and coming to
   rest (:func:`contacts`), energy between flights (:func:`energy`), sleeping (:func:`sleeping`) and the air
   (:func:`air`).

:class:`Numbers` is what the chapter reports, under the names ``data.figure2``, ``data.figure3``,
``data.figure3.bounces`` and so on; the page glues the rest of :class:`DataChapter` (its sentences, settings,
counts and tables) with ``study.book.publish`` and draws its figures from the result's data.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from study import CLASSES
from study.learn.metrics import bootstrap_accuracy
from study.report import verdicts
from study.report.data import Figure3, Numbers, RuleName
from study.report.reported import Number, Verdict, number
from study.report.text import Table, pct, pct_ci
from study.runs.stats import mean_difference
from study.see import render
from study.simulate import checks, contact, measure, synth
from study.simulate.data import Dataset, Split
from study.simulate.synth import SynthConfig

RULES: tuple[RuleName, ...] = ("bounces", "time_to_rest", "distance", "max_height_after_1s")
"""The one-number summaries a simple rule thresholds here (``measure.FEATURES``); the fall's acceleration, which
reads the air's drag, is left out on purpose (the chapter on cues tries it)."""
Claim = Literal["bounces", "time_to_rest"]
CLAIMS: dict[Claim, str] = {"bounces": "light objects bounce more", "time_to_rest": "light objects take longer to stop"}
"""What the paper reads off its Figure 3, per summary: light minus heavy is positive."""
STATS: tuple[str, ...] = ("bounces", "time_to_rest", "distance")
"""The summaries of the data statistics (table and histograms)."""
FILMSTRIP_TIMES: tuple[float, ...] = (0.0, 0.15, 0.3, 0.45, 0.6, 0.8, 1.0, 1.3)
"""Seconds: the frames of Figure 2's filmstrip."""
KEYFRAMES = 6
"""Key-frame intervals of the paper's launch before the physics engine takes over (frames 1-7)."""
RESTITUTIONS = np.linspace(0.1, 0.85, 7)
"""Restitutions the drops and the timestep convergence are checked at."""
DROPS: tuple[tuple[float, float], ...] = ((0.6, 0.05), (1.0, 1.0), (1.4, 20.0))
"""(drop height m, mass kg) of the flat drops checked at each restitution."""
AIR_MASSES: tuple[float, float] = (0.05, 20.0)
"""kg: the one throw simulated as a light and as a heavy object, to show what the air does with mass."""
RISE = 1e-3
"""A flight's energy that exceeds the previous flight's by more than this share of the first flight's gained
energy at the impact between them."""

SOURCES: dict[tuple[str, str], str] = {
    ("light", "mass"): "a 20 cm box: EPS foam block, 8 L at 10–35 kg/m³ {EUMEPS}, 0.08–0.28 kg; empty corrugated "
                       "box, about 0.3 m² of board at 0.4–0.8 kg/m² {FEFCO}, 0.12–0.24 kg; empty polypropylene box, "
                       "0.24 m² of 1.5–3 mm wall at 905 kg/m³, 0.33–0.65 kg",
    ("light", "restitution"): "a flexible foam returns 35–65 % of a drop's height in the standard ball-rebound test "
                              "{ISO8307}, e ≈ 0.6–0.8 (our upper end); a thin-walled box flexes and loses more (our "
                              "estimate, 0.35–0.6: no drop test of an empty box on asphalt is published that we could "
                              "find)",
    ("light", "friction"): "hard plastic, cardboard or foam on concrete ≈ 0.3–0.7 (estimate); wood on concrete 0.62 "
                           "{ToolBox} for comparison",
    ("heavy", "mass"): "pine cube of this size ≈ 4 kg (500 kg/m³ × 8 L), oak ≈ 6 kg, a full small gas cylinder ≈ "
                       "15–25 kg",
    ("heavy", "restitution"): "rock on asphalt, concrete or rock: normal restitution ≈ 0.2 for near-normal impacts "
                              "{Wyllie}; wooden ball on a hard floor 0.6 {Factbook} (a block landing on a face or edge "
                              "loses more)",
    ("heavy", "friction"): "wood on concrete 0.62 {ToolBox}; metals on concrete somewhat lower",
}
"""Where each class prior's range comes from, with its references as ``{Key}`` (:data:`CITES`)."""
CITES: dict[str, str] = {"{EUMEPS}": "{cite:p}`eumeps2024eps`", "{FEFCO}": "{cite:p}`fefco2021code`",
                         "{ISO8307}": "{cite:p}`iso8307`", "{Factbook}": "{cite:p}`elert2006restitution`",
                         "{ToolBox}": "{cite:p}`engtoolbox2004friction`", "{Wyllie}": "{cite:p}`wyllie2014rockfall`"}
"""Each reference of :data:`SOURCES` as the book cites it."""
UNITS: dict[str, str] = {"mass": "kg (log-uniform)", "restitution": "(uniform)", "friction": "(uniform)"}
"""How each class parameter is drawn, after its range."""


# ---------------------------------------------------------------------------------------------
# What the chapter reports


# ---------------------------------------------------------------------------------------------
# The priors, Figure 2, Figure 3, the data, the simple rules


def prior_table(cfg: SynthConfig) -> Table:
    """The class priors (mass, restitution, friction and the density they imply) and the launch prior, with
    their sources, as the book cites them."""
    rows = []
    volume = 8 * float(np.prod(cfg.shape.size))  # m³ of the box (size: half-extents)
    for name in CLASSES:
        prior = cfg.prior(name)
        for field, unit in UNITS.items():
            lo, hi = getattr(prior, field)
            rows.append({"class": name, "parameter": field, "range": f"{lo:g} – {hi:g} {unit}",
                         "source": SOURCES[name, field]})
        rows.append({"class": name, "parameter": "density (mass / volume)",
                     "range": f"{prior.mass[0] / volume:.3g} – {prior.mass[1] / volume:.4g} kg/m³",
                     "source": "follows from the mass range and the box's volume"})
    launch = cfg.launch
    rows += [
        {"class": "both", "parameter": "launch height (centre)",
         "range": f"{launch.height[0]:g} – {launch.height[1]:g} m", "source": "a car's boot to a lorry's bed"},
        {"class": "both", "parameter": "horizontal speed",
         "range": f"{launch.horizontal_speed[0]:g} – {launch.horizontal_speed[1]:g} m/s",
         "source": "thrown or dropped from a moving load, relative to the road"},
        {"class": "both", "parameter": "vertical velocity",
         "range": f"{launch.vertical_speed[0]:g} – {launch.vertical_speed[1]:g} m/s", "source": "tossed up or down"},
        {"class": "both", "parameter": "spin (each axis)", "range": f"±{launch.spin:.2f} rad/s",
         "source": "about one turn per second"},
    ]
    for r in rows:
        for k, v in CITES.items():
            r["source"] = r["source"].replace(k, v)
    return Table(rows, {"class": "class", "parameter": "parameter", "range": "range", "source": "source"})


@dataclass(frozen=True)
class Filmstrip:
    """The paper's Figure 2 for one light training throw: frames of it, and its recorded height."""

    index: int
    """The throw, an index into the training split."""
    times: np.ndarray
    """(k,) seconds: the frames' times."""
    frames: tuple[np.ndarray, ...]
    """k MuJoCo frames, each (240, 320, 3) uint8 RGB, from one fixed camera framing the whole throw."""
    t: np.ndarray
    """(T,) seconds since recording started."""
    z: np.ndarray
    """(T,) metres: the recorded height of the centre."""
    lead: np.ndarray
    """(KEYFRAMES + 1,) seconds, up to 0: the paper's key-frame launch, drawn for comparison (not simulated)."""
    lead_z: np.ndarray
    """(KEYFRAMES + 1,) metres: the height of that linear launch, ending in the simulation's start."""
    start_z: float
    """Metres: the height at which the physics takes over and recording starts."""

    @property
    def titles(self) -> tuple[str, ...]:
        """Each frame's time, as its title."""
        return tuple(f"t = {t:.2f} s" for t in self.times)


def filmstrip(cfg: SynthConfig, ds: Dataset, times: tuple[float, ...] = FILMSTRIP_TIMES) -> Filmstrip:
    """Figure 2's data: the first light throw of the training split rendered at ``times`` (seconds)."""
    train = ds.train
    i = int(np.flatnonzero(train.y == 0)[0])
    at = np.array(times)
    frames = render.filmstrip(cfg, train.params, i, at, width=320, height=240)
    lead = np.arange(-KEYFRAMES, 1) / cfg.fps
    p0, v0 = train.params["qpos0"][i, :3], train.params["qvel0"][i, :3]
    return Filmstrip(i, at, tuple(frames), ds.times, train.x[i, :, 2], lead, p0[2] + v0[2] * lead, float(p0[2]))


def sample_throws(y: np.ndarray, n_examples: int, seed: int) -> dict[str, np.ndarray]:
    """Figure 3's throws: ``n_examples`` of each class drawn at random (``seed``) from labels ``y`` (n,), heavy
    first as in the paper; class name -> indices (k,) int."""
    rng = np.random.default_rng(seed)
    picks = {}
    for name in ("heavy", "light"):
        pool = np.flatnonzero(y == CLASSES.index(name))
        picks[name] = rng.choice(pool, size=min(n_examples, len(pool)), replace=False)
    return picks


def figure3(test_features: dict[str, np.ndarray], y: np.ndarray) -> Figure3:
    """The paper's two claims of Figure 3 on the test throws: light minus heavy in bounces and in time to rest,
    each ordered against the claim that it is positive (a count and a time: no margin in points), then both.

    ``test_features``: ``measure.features`` of the test split, name -> (n,); ``y``: (n,) labels."""
    light, heavy = y == 0, y == 1
    diffs = {}
    for name, claim in CLAIMS.items():
        dv = mean_difference(test_features[name][light], test_features[name][heavy])
        diffs[name] = number(dv, f"light minus heavy, test throws: {measure.FEATURES[name]} (the paper: {claim})",
                             unit="count" if name == "bounces" else "s",
                             decision=verdicts.order(dv, +1, in_points=False))
    both = verdicts.combined([n.decision for n in diffs.values()])  # type: ignore[misc]
    return Figure3(diffs["bounces"], diffs["time_to_rest"],
                   Verdict(both, "the classes' trajectories differ as the paper's Figure 3 shows them"))


def figure2() -> Verdict:
    """The paper's Figure 2 has no number: judged by what it shows."""
    return Verdict(verdicts.qualitative(
        "a trajectory starts from a launch state and continues under the physics engine: the launch and the "
        "recorded height of one throw are shown, with MuJoCo frames of it"),
        "the paper's Figure 2: how a trajectory is made")


def stats_table(features: dict[str, np.ndarray], y: np.ndarray) -> Table:
    """Median and interquartile range of each of :data:`STATS` per class: ``features`` name -> (n,), ``y`` (n,)."""
    rows = []
    for label, cname in enumerate(CLASSES):
        sel = y == label
        row = {"class": cname}
        for name in STATS:
            q = np.percentile(features[name][sel], [25, 50, 75])
            row[name] = f"{q[1]:.2f} ({q[0]:.2f}–{q[2]:.2f})"
        rows.append(row)
    return Table(rows, {"class": "class", **{name: measure.FEATURES[name] for name in STATS}})


@dataclass(frozen=True)
class SimpleRules:
    """The best threshold on each summary (``measure.best_threshold_rule``) and the one the training split picks."""

    rules: dict[RuleName, dict]
    """Per summary: threshold, direction, train and test accuracy, ``correct`` (n_test,) bool."""
    best: RuleName
    """The summary whose rule has the highest training accuracy (``measure.best_rule``), never chosen on test."""

    def numbers(self) -> dict[RuleName, Number]:
        """Each rule's test accuracy with its bootstrap interval over the test throws."""
        return {name: number(bootstrap_accuracy(r["correct"]),
                             f"test accuracy of the best threshold on {measure.FEATURES[name]}")
                for name, r in self.rules.items()}

    def table(self, numbers: dict[RuleName, Number]) -> Table:
        """Each rule in words, its training accuracy and its test accuracy with ``numbers``' intervals."""
        rows = [{"rule": f"heavy if {measure.FEATURES[name]} {'>' if r['direction'] == '>' else '≤'} "
                         f"{r['threshold']:.2f}",
                 "train": pct(r["train_accuracy"]), "test": pct_ci(numbers[name].interval)}
                for name, r in self.rules.items()]
        return Table(rows, {"rule": "rule (threshold chosen on train)", "train": "train accuracy",
                            "test": "test accuracy [95 % CI]"})


def simple_rules(train_features: dict[str, np.ndarray], y_train: np.ndarray, test_features: dict[str, np.ndarray],
                 y_test: np.ndarray, names: tuple[RuleName, ...] = RULES) -> SimpleRules:
    """The best threshold on each of ``names``, chosen on the training split's features (name -> (n,)) and labels,
    scored on the test split's; the best rule by training accuracy."""
    rules = {name: measure.best_threshold_rule(train_features[name], y_train, test_features[name], y_test)
             for name in names}
    best = measure.best_rule([{"feature": name, **r} for name, r in rules.items()])["feature"]
    return SimpleRules(rules, best)


# ---------------------------------------------------------------------------------------------
# The physics checks, each a typed result


@dataclass(frozen=True)
class FreeFlight:
    """Free flight against the analytic parabola (air off, launched too high to touch the ground in 1 s)."""

    error: float
    """Metres: the largest distance from ``p0 + v0 t - g t²/2`` over one second, over every launch."""
    n_launches: int
    """Launches checked."""
    naive_sag: float
    """Metres: how far a flight started without the half-step stagger sags in one second (g Δt / 2 · 1 s)."""


def free_flight(cfg: SynthConfig, seed: int, n: int = 8) -> FreeFlight:
    """:func:`study.simulate.checks.free_flight_error` for ``n`` launches of the prior, 12-15 m up."""
    high = cfg.replace(launch=synth.LaunchPrior(height=(12.0, 15.0)))
    qpos, qvel = synth.sample_launch(high.launch, n, np.random.default_rng(seed))
    error = max(checks.free_flight_error(cfg, qpos[k], qvel[k]) for k in range(n))
    return FreeFlight(float(error), n, synth.GRAVITY * cfg.timestep / 2)


@dataclass(frozen=True)
class Restitution:
    """The restitution: its calibration from contact damping, drops against the value set, and the timestep."""

    damping: np.ndarray
    """(k,) 1/s: the calibration's contact dampings."""
    measured: np.ndarray
    """(k,) the restitution measured at each (mean of 8 impact phases)."""
    linear: np.ndarray
    """(k,) the linear damped oscillator's restitution at each (the textbook guide)."""
    drops: np.ndarray
    """(m, 3): restitution set, restitution measured from successive apex heights, bounce index (0: drop -> 1)."""
    convergence: dict[str, np.ndarray]
    """``"set"``, ``"dt"``, ``"dt/2"``: (j,) the first bounce's restitution at the timestep and at half of it."""
    timestep: float
    """Seconds: the simulation's step."""

    @property
    def drop_error(self) -> float:
        """The largest |measured - set| over every drop and bounce."""
        return float(np.abs(self.drops[:, 1] - self.drops[:, 0]).max())

    @property
    def convergence_error(self) -> float:
        """The largest change of the measured restitution when the timestep is halved."""
        return float(np.abs(self.convergence["dt"] - self.convergence["dt/2"]).max())

    @property
    def timestep_label(self) -> str:
        """The step in words, for a legend."""
        return f"Δt = {1000 * self.timestep:.3f} ms"


def restitution(cfg: SynthConfig) -> Restitution:
    """The calibration table, flat drops (:data:`DROPS`, 3 bounces) and the timestep convergence at
    :data:`RESTITUTIONS`."""
    b, e = contact.calibration_table(cfg.shape, cfg.stiffness, cfg.timestep)
    drops = [(r, m, k) for r in RESTITUTIONS for drop, mass in DROPS
             for k, m in enumerate(checks.restitution_from_drops(cfg, r, drop=drop, mass=mass, bounces=3))]
    linear = np.array([contact.linear_restitution(x, cfg.stiffness) for x in b])
    return Restitution(b, e, linear, np.array(drops), checks.convergence(cfg, RESTITUTIONS), cfg.timestep)


def first_of_each_class(y: np.ndarray, n: int) -> list[int]:
    """The first ``n`` indices of each class in labels ``y`` (n,), light then heavy."""
    return [int(j) for label in (0, 1) for j in np.flatnonzero(y == label)[:n]]


@dataclass(frozen=True)
class Contacts:
    """Penetration and coming to rest, from throws traced step by step (:func:`study.simulate.checks.trace`)."""

    traces: tuple[checks.Trace, ...]
    """Every step of each throw."""
    classes: tuple[str, ...]
    """Each throw's class."""
    bound: float
    """Metres: the penetration bound ``v_max / sqrt(k d_min)`` at the fastest impact the launch prior allows."""
    max_impact_speed: float
    """m/s: that impact speed, spin included."""
    timestep: float
    """Seconds: the simulation's step."""

    @property
    def deepest(self) -> float:
        """Metres: the deepest penetration seen."""
        return float(max(tr.depth.max() for tr in self.traces))

    @property
    def last_half_speeds(self) -> list[np.ndarray]:
        """Each throw's speeds over its last half second, m/s."""
        return [tr.speed[-int(0.5 / self.timestep):] for tr in self.traces]

    @property
    def rest_speed(self) -> float:
        """m/s: the fastest any throw moves in its last half second."""
        return float(max(v.max() for v in self.last_half_speeds))

    @property
    def n_still(self) -> int:
        """Throws that lie exactly still (asleep) for their whole last half second."""
        return int(sum(v.max() == 0 for v in self.last_half_speeds))


def trace_config(cfg: SynthConfig) -> SynthConfig:
    """The config the step-by-step traces run: at most 8 s."""
    return cfg.replace(duration=min(cfg.duration, 8.0))


def contacts(cfg: SynthConfig, train: Split, n: int = 4) -> Contacts:
    """The first ``n`` throws of each class of the training split, traced."""
    picks = first_of_each_class(train.y, n)
    traces = tuple(checks.trace(trace_config(cfg), train.params, j) for j in picks)
    v = cfg.max_impact_speed()
    return Contacts(traces, tuple(CLASSES[train.y[j]] for j in picks),
                    contact.penetration_bound(v, cfg.stiffness), v, cfg.timestep)


def largest_rise(e: np.ndarray) -> float:
    """Largest rise of a flight's energy over the previous flight's, relative to the first (0: one flight or
    none); ``e``: (k,) joules, each flight's mean energy."""
    return float(np.max(np.diff(e)) / e[0]) if len(e) > 1 else 0.0


@dataclass(frozen=True)
class Energy:
    """Mechanical energy of each flight phase, air off: training throws with their friction, and throws of the
    same priors without friction."""

    with_friction: tuple[np.ndarray, ...]
    """Per training throw, (k,) joules: each flight's mean energy."""
    classes: tuple[str, ...]
    """Each of those throws' class."""
    frictionless: tuple[np.ndarray, ...]
    """The same for the frictionless throws."""

    @property
    def series(self) -> dict[str, tuple[np.ndarray, ...]]:
        """Both sets by name, for the figure."""
        return {"with friction": self.with_friction, "frictionless": self.frictionless}

    @property
    def rises(self) -> list[float]:
        """:func:`largest_rise` of each throw with friction."""
        return [largest_rise(e) for e in self.with_friction]

    @property
    def frictionless_rises(self) -> list[float]:
        """:func:`largest_rise` of each frictionless throw."""
        return [largest_rise(e) for e in self.frictionless]

    @property
    def gaining(self) -> dict[str, tuple[int, int]]:
        """Per class: (throws with friction that gain energy at some impact, throws of that class)."""
        return {c: (sum(r > RISE for r, k in zip(self.rises, self.classes) if k == c), self.classes.count(c))
                for c in CLASSES}

    @property
    def by_class(self) -> str:
        """Whether the energy gained with friction touches both classes alike, in words."""
        gaining = self.gaining
        counts = " and ".join(f"{g} of {n} {c}" for c, (g, n) in gaining.items())
        if all(g for g, _ in gaining.values()):
            return f"It touches both classes: {counts} throws gain energy at some impact."
        if any(g for g, _ in gaining.values()):
            return (f"It does not touch the classes alike: {counts} throws gain energy at some impact, so it is one "
                    "more difference between them that a classifier could use, though not one a real object shows.")
        return "None of these throws gains energy."


def energy(cfg: SynthConfig, train: Split, seed: int, n: int = 16, n_frictionless: int = 4) -> Energy:
    """Flight energies of the first ``n`` training throws of each class, air off, and of ``n_frictionless`` a
    class drawn from the same priors with friction 0 (``seed``'s training stream)."""
    no_air = trace_config(cfg).replace(air=False)
    frictionless = no_air.replace(light=synth.ClassPrior(cfg.light.mass, cfg.light.restitution, (0.0, 0.0)),
                                  heavy=synth.ClassPrior(cfg.heavy.mass, cfg.heavy.restitution, (0.0, 0.0)))
    fl_params = synth.sample_split(frictionless.replace(n_train=n_frictionless, n_test=1), seed, "train")
    picks = first_of_each_class(train.y, n)
    return Energy(tuple(checks.trace(no_air, train.params, j).flight_energies() for j in picks),
                  tuple(CLASSES[train.y[j]] for j in picks),
                  tuple(checks.trace(frictionless, fl_params, j).flight_energies() for j in range(2 * n_frictionless)))


@dataclass(frozen=True)
class Sleeping:
    """What letting resting objects sleep changes: the same throws simulated with the config's sleeping and
    awake (:func:`study.simulate.checks.sleep_effect`)."""

    n: int
    """Throws simulated both ways."""
    max_diff: np.ndarray
    """(n,) metres: the largest distance between the two centres over the record."""
    first_diff: np.ndarray
    """(n,) seconds: the first frame at which they differ at all (NaN: never)."""
    time_to_rest: np.ndarray
    """(n,) seconds: the awake throw's time to rest."""
    last_speed_asleep: np.ndarray
    """(n,) m/s: the fastest frame-to-frame speed in the record's last second, with sleeping."""
    last_speed_awake: np.ndarray
    """(n,) m/s: the same, awake."""
    seconds_asleep: float
    """Wall time of the simulation with sleeping, one thread."""
    seconds_awake: float
    """Wall time awake."""

    @property
    def n_over_mm(self) -> int:
        """Throws whose centres differ by more than 1 mm."""
        return int(np.sum(self.max_diff > 1e-3))

    @property
    def n_early(self) -> int:
        """Throws whose positions differ before the object has come to rest."""
        return int(np.sum(self.first_diff < self.time_to_rest))

    @property
    def n_frozen(self) -> int:
        """Throws that do not move at all in the last second, with sleeping."""
        return int(np.sum(self.last_speed_asleep == 0))


def sleeping(cfg: SynthConfig, train: Split, n: int = 32) -> Sleeping:
    """The first ``n`` training throws of each class, asleep and awake."""
    s = checks.sleep_effect(cfg, train.params, first_of_each_class(train.y, n), threads=1)
    return Sleeping(len(s["max_diff"]), s["max_diff"], s["first_diff"], s["time_to_rest"],  # type: ignore[arg-type]
                    s["last_speed_asleep"], s["last_speed_awake"],  # type: ignore[arg-type]
                    float(s["seconds_asleep"]), float(s["seconds_awake"]))  # type: ignore[arg-type]


@dataclass(frozen=True)
class Air:
    """The first light training throw simulated with :data:`AIR_MASSES`, the same contact: drag is the only way
    mass enters the motion."""

    x: np.ndarray
    """(2, T, 3) float32 metres: the throw as each mass, at most 3 s."""
    masses: tuple[float, float]
    """kg."""

    @property
    def max_height_difference(self) -> float:
        """Metres: the largest difference between the two heights."""
        return float(np.abs(self.x[0, :, 2] - self.x[1, :, 2]).max())


def air(cfg: SynthConfig, train: Split, masses: tuple[float, float] = AIR_MASSES) -> Air:
    """:class:`Air` for the first light throw of ``train``."""
    j = int(np.flatnonzero(train.y == 0)[0])
    pair = {k: v[[j, j]].copy() for k, v in train.params.items()}
    pair["mass"] = np.array(masses)
    return Air(synth.simulate(cfg.replace(duration=min(cfg.duration, 3.0)), pair, progress=False), masses)


# ---------------------------------------------------------------------------------------------
# The chapter's result


@dataclass(frozen=True)
class DataChapter:
    """Everything the chapter shows: its numbers (:attr:`numbers`), tables, settings and sentences, and the data
    its figures draw. Properties are in the units their names say (``_mm``: millimetres, ``_pct``: per cent)."""

    numbers: Numbers
    """What the chapter reports (the results file's ``data.*``)."""
    config: SynthConfig
    """The data set's config."""
    prior_table: Table
    """The priors with their sources."""
    stats_table: Table
    """Median and interquartile range of each summary per class, training split."""
    rules_table: Table
    """The best threshold on each summary."""
    filmstrip: Filmstrip
    """Figure 2's data."""
    samples: dict[str, np.ndarray]
    """Figure 3's throws: class -> indices into the training split."""
    features: dict[str, np.ndarray]
    """``measure.features`` of the training split: name -> (n,)."""
    rules: SimpleRules
    """The simple rules and the one the training split picks."""
    free_flight: FreeFlight
    """Free flight against the parabola."""
    restitution: Restitution
    """The restitution's calibration, drops and timestep convergence."""
    contacts: Contacts
    """Penetration and coming to rest."""
    energy: Energy
    """Energy between flights."""
    sleeping: Sleeping
    """What sleeping changes."""
    air: Air
    """What the air does with mass."""

    # The scene's settings ----------------------------------------------------------------------

    @property
    def n_train(self) -> int:
        """Training trajectories per class."""
        return self.config.n_train

    @property
    def n_test(self) -> int:
        """Test trajectories per class."""
        return self.config.n_test

    @property
    def n_total(self) -> int:
        """Trajectories of the ``paper`` preset, both splits and classes."""
        p = SynthConfig.preset("paper")
        return 2 * (p.n_train + p.n_test)

    @property
    def duration(self) -> float:
        """Seconds of each record."""
        return float(self.config.duration)

    @property
    def fps(self) -> float:
        """Frames per second."""
        return float(self.config.fps)

    @property
    def n_frames(self) -> int:
        return self.config.n_frames

    @property
    def dt_ms(self) -> float:
        """The timestep, milliseconds."""
        return 1000 * self.config.timestep

    @property
    def steps_per_frame(self) -> int:
        return self.config.steps_per_frame

    @property
    def stiffness(self) -> float:
        """The contact's stiffness k, s⁻²."""
        return float(self.config.stiffness)

    @property
    def contact_ms(self) -> float:
        """How long a contact lasts, π / sqrt(k), milliseconds."""
        return 1000 * math.pi / math.sqrt(self.config.stiffness)

    @property
    def resolution(self) -> float:
        """sqrt(k) Δt: under 0.3 the stiff contact is resolved."""
        return math.sqrt(self.config.stiffness) * self.config.timestep

    @property
    def edge_cm(self) -> float:
        """The cube's edge, centimetres."""
        return 200 * float(self.config.shape.size[0])

    # Figure 3 and the bounce ---------------------------------------------------------------------

    @property
    def fig3_bounces(self) -> str:
        """Light minus heavy in bounces, with its interval."""
        n = self.numbers.figure3.bounces
        return f"{n.value:+.2f} [{n.lo:+.2f}, {n.hi:+.2f}]"

    @property
    def fig3_rest(self) -> str:
        """Light minus heavy in time to rest, with its interval."""
        n = self.numbers.figure3.time_to_rest
        return f"{n.value:+.2f} s [{n.lo:+.2f}, {n.hi:+.2f}]"

    @property
    def min_rise_cm(self) -> float:
        """The rise that makes a bounce, centimetres."""
        return 100 * measure.MIN_RISE

    @property
    def min_rise_ms(self) -> float:
        """How long a rebound of that height stays in the air, milliseconds."""
        return 1000 * 2 * math.sqrt(2 * measure.MIN_RISE / synth.GRAVITY)

    @property
    def min_rise_frames(self) -> float:
        """The same in camera frames."""
        return self.min_rise_ms / 1000 * self.fps

    @property
    def rock_cm(self) -> float:
        """How far the cube's centre rises when it rocks from a face onto an edge, centimetres."""
        return 100 * (self.config.shape.bounding_radius - self.config.shape.rest_height)

    # The simple rules ----------------------------------------------------------------------------

    @property
    def best_rule(self) -> str:
        """The best rule's summary, in words."""
        return measure.FEATURES[self.rules.best].split(",")[0]

    @property
    def best_rule_acc(self) -> float:
        """The best rule's test accuracy, per cent."""
        return 100 * self.rules.rules[self.rules.best]["test_accuracy"]

    @property
    def bounce_rule_acc(self) -> float:
        """Counting bounces: the test accuracy, per cent."""
        return 100 * self.rules.rules["bounces"]["test_accuracy"]

    @property
    def best_rule_wrong(self) -> int:
        """Test throws the best rule gets wrong."""
        return int((~self.rules.rules[self.rules.best]["correct"]).sum())

    @property
    def n_test_throws(self) -> int:
        """Test throws, both classes."""
        return len(self.rules.rules[self.rules.best]["correct"])

    # The physics checks --------------------------------------------------------------------------

    @property
    def flight_err(self) -> float:
        """Metres: free flight's largest distance from the parabola."""
        return self.free_flight.error

    @property
    def flight_err_naive_mm(self) -> float:
        return 1000 * self.free_flight.naive_sag

    @property
    def conv_max(self) -> float:
        return self.restitution.convergence_error

    @property
    def drop_err(self) -> float:
        return self.restitution.drop_error

    @property
    def pen_bound_mm(self) -> float:
        return 1000 * self.contacts.bound

    @property
    def pen_max_mm(self) -> float:
        return 1000 * self.contacts.deepest

    @property
    def v_max(self) -> float:
        """m/s: the fastest impact the launch prior allows."""
        return self.contacts.max_impact_speed

    @property
    def rest_speed_mm(self) -> float:
        """mm/s: the fastest a traced throw moves in its last half second."""
        return 1000 * self.contacts.rest_speed

    @property
    def n_still(self) -> int:
        return self.contacts.n_still

    @property
    def n_traces(self) -> int:
        return len(self.contacts.traces)

    @property
    def fl_max_rise(self) -> float:
        """Per cent of the first flight's energy: the largest rise without friction."""
        return 100 * max(self.energy.frictionless_rises)

    @property
    def fr_max_rise(self) -> float:
        """Per cent: the largest rise with friction."""
        return 100 * max(self.energy.rises)

    @property
    def fr_n_rise(self) -> int:
        """Throws with friction that gain energy at some impact."""
        return sum(r > RISE for r in self.energy.rises)

    @property
    def fr_n(self) -> int:
        return len(self.energy.with_friction)

    @property
    def fr_by_class(self) -> str:
        return self.energy.by_class

    @property
    def rest_pct(self) -> float:
        """Per cent of the training set's simulated time after its objects have come to rest."""
        return 100 * (1 - float(self.features["time_to_rest"].mean()) / self.config.duration)

    @property
    def rest_def_cm(self) -> float:
        """cm/s: the speed under which an object is at rest."""
        return 100 * measure.REST_SPEED

    @property
    def sleep_tol_mm(self) -> float:
        """mm/s: the sleep tolerance."""
        return 1000 * self.config.sleep_tolerance

    @property
    def sleep_tol_frame_mm(self) -> float:
        """mm of motion per camera frame at that tolerance."""
        return 1000 * self.config.sleep_tolerance / self.config.fps

    @property
    def sleep_steps(self) -> int:
        """Steps under the tolerance before an object sleeps."""
        return int(synth.SLEEP_STEPS)

    @property
    def sleep_tol_max_mm(self) -> float:
        """mm/s: the largest tolerance the config allows at its step."""
        return 1000 * synth.max_sleep_tolerance(self.config.timestep)

    @property
    def pixel_mm(self) -> float:
        """mm per pixel of the real-world chapter's camera (side, 240 px high) at the object, 4 m away."""
        return 1000 * render.metres_per_pixel(render.class_model("light"), "side", 240, depth=4.0)

    @property
    def sleep_n(self) -> int:
        return self.sleeping.n

    @property
    def sleep_max_mm(self) -> float:
        return 1000 * float(self.sleeping.max_diff.max())

    @property
    def sleep_n_mm(self) -> int:
        return self.sleeping.n_over_mm

    @property
    def sleep_n_early(self) -> int:
        return self.sleeping.n_early

    @property
    def creep_mm(self) -> float:
        """mm/s: the fastest an awake object moves in the record's last second."""
        return 1000 * float(self.sleeping.last_speed_awake.max())

    @property
    def n_frozen(self) -> int:
        return self.sleeping.n_frozen

    @property
    def sleep_s_awake(self) -> float:
        return self.sleeping.seconds_awake

    @property
    def sleep_s_asleep(self) -> float:
        return self.sleeping.seconds_asleep

    @property
    def sleep_speedup(self) -> float:
        return self.sleeping.seconds_awake / self.sleeping.seconds_asleep

    @property
    def air_dz_cm(self) -> float:
        return 100 * self.air.max_height_difference


def compute(ds: Dataset, n_examples: int = 5) -> DataChapter:
    """The chapter *The data* on ``ds`` (its config and seed read from its provenance); ``n_examples``: throws
    per class in Figure 3's counterpart. Every physics check simulates afresh (seconds at the smoke preset; the
    step-by-step traces of the paper's 10 s records take longer)."""
    cfg = SynthConfig.from_dict(ds.meta["config"])
    seed = int(ds.meta["seed"])
    train, test = ds.train, ds.test
    feats = measure.features(train.x, ds.fps)
    test_feats = measure.features(test.x, ds.fps)
    rules = simple_rules(feats, train.y, test_feats, test.y)
    rule_numbers = rules.numbers()
    numbers = Numbers(figure2(), figure3(test_feats, test.y), rule_numbers)
    return DataChapter(
        numbers, cfg, prior_table(cfg), stats_table(feats, train.y), rules.table(rule_numbers),
        filmstrip(cfg, ds), sample_throws(train.y, n_examples, seed), feats, rules,
        free_flight(cfg, seed), restitution(cfg), contacts(cfg, train), energy(cfg, train, seed),
        sleeping(cfg, train), air(cfg, train))
