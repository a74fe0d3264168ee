"""What the motion allows: every learner, trained and tested under each camera, against the exact ceiling.

The table of the chapter "What the motion allows" has a row per learner and a column per condition: the air
on or off, and the positions exact or observed by a camera whose error is one pixel of a 1080-row camera at
4 m, the tracker's calibrated error, or one pixel of the same camera at 55 m (with the calibrated share of
lost frames in every observed column). Each learner is trained on the condition it is tested on:

- the networks (:data:`NETWORKS`) with ``TrainConfig.observe = 'fixed'`` at the column's noise (a fresh draw
  every epoch; validation observed the same way), three seeds or more;
- MiniRocket on one observed draw of the training split, once per seed;
- the physics baseline and the best one-feature rule fitted once on that draw;

and one more row, Table 1's network trained on exact positions and tested observed. Every learner of a
column is scored on the same observed test trajectories (one seeded draw per column), so two learners
compare paired. Z only (what one camera gives), the first T seconds of Table 1.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from study.experiments import ceiling, cues
from study.learn import baseline
from study.learn.config import TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy, bootstrap_difference
from study.simulate import observe
from study.simulate.data import Dataset, Split

ROWS_1080 = 1080
"""Image rows of the camera whose pixel sets the two ends of the noise sweep."""
NEAR, FAR = 4.0, 55.0
"""Camera distances, metres: as the rendered videos are filmed, and where one pixel is about 4 cm."""
RULE_FEATURES = ("bounces", "max_height_after_1s", "fall_acceleration")
"""The one-feature rules a height alone allows (``study.simulate.measure.FEATURES``)."""
NETWORKS = ("lstm_positions", "lstm_velocity", "gru_velocity")
"""The trained networks, each at its own configuration."""
LEARNERS = (*NETWORKS, "lstm_exact_trained", "minirocket", "physics", "rule")
"""Every row of the table, the ceiling aside."""
NAMES = {"lstm_positions": "peephole LSTM, positions (the paper's)", "lstm_velocity": "peephole LSTM, with velocity",
         "gru_velocity": "GRU, with velocity", "lstm_exact_trained": "peephole LSTM, positions, trained exact",
         "minirocket": "MiniRocket, positions", "physics": "physics baseline", "rule": "best one-feature rule"}
"""Each learner in words."""


VIEWS = ("exact", "near", "calibrated", "far")
"""The camera conditions of each air setting, in the table's order."""


@dataclass(frozen=True)
class Column:
    """One condition of the table: the air, and the camera's error (None: exact positions)."""

    air: bool
    """Air drag and added mass on (the study's data) or off (the same throws without air)."""
    name: str
    """One of :data:`VIEWS`."""
    noise: float | None
    """The camera and tracker's position error, metres; None for exact positions."""
    drop: float = 0.0
    """The share of frames the tracker loses."""
    label: str = ""
    """What the column is, in words, for the table's header and caption."""

    @property
    def key(self) -> str:
        return f"{'air_on' if self.air else 'air_off'}.{self.name}"

    def observation(self) -> observe.Observation | None:
        return None if self.noise is None else observe.Observation(noise=self.noise, drop=self.drop)

    def inputs(self, ds: Dataset, T: int) -> tuple[np.ndarray, np.ndarray]:
        """(training, test) inputs of ``ds``'s first ``T`` frames, (n, T, 3) metres: exact, or observed with
        the column's error. Each column draws its own noise, the same for every learner and every engine (the
        seed depends on the column alone), the training split's apart from the test split's."""
        ob = self.observation()
        if ob is None:
            return ds.train.x[:, :T], ds.test.x[:, :T]
        salt = 100 * (2 if self.air else 3) + VIEWS.index(self.name)
        return ob.observe(ds.train.x[:, :T], ds.fps, seed=salt + 50), ob.observe(ds.test.x[:, :T], ds.fps, seed=salt)


def columns(calibration: dict[str, float]) -> list[Column]:
    """The table's eight columns, from the tracker's calibration (``Runner.calibration``): air on and off, each
    exact and at one pixel of a 1080-row camera at :data:`NEAR` m, at the calibrated error, and at one pixel
    at :data:`FAR` m."""
    near = observe.Camera(distance=NEAR, rows=ROWS_1080).metres_per_pixel()
    far = observe.Camera(distance=FAR, rows=ROWS_1080).metres_per_pixel()
    cal_px = calibration["noise_px"]
    drop = calibration["drop"]
    views = [("exact", None, "exact positions"),
             ("near", near, f"1 px of a {ROWS_1080}-row camera at {NEAR:g} m ({1000 * near:.1f} mm)"),
             ("calibrated", calibration["noise_m"],
              f"the calibrated tracker, {cal_px:.2f} px at 4 m ({1000 * calibration['noise_m']:.1f} mm)"),
             ("far", far, f"1 px of a {ROWS_1080}-row camera at {FAR:g} m ({1000 * far:.1f} mm)")]
    return [Column(air, name, noise, 0.0 if noise is None else drop, label) for air in (True, False)
            for name, noise, label in views]


def trained_config(cfg: TrainConfig, column: Column) -> TrainConfig:
    """``cfg`` trained on the column's condition: exact, or observed with its noise and lost frames."""
    if column.noise is None:
        return dataclasses.replace(cfg, dims="z")
    return dataclasses.replace(cfg, dims="z", observe="fixed", observe_noise=column.noise, observe_drop=column.drop)


def network_configs(cfgs: dict[str, TrainConfig], column: Column) -> dict[str, TrainConfig]:
    """The config of every network row in ``column``: each of :data:`NETWORKS` trained on the column's condition,
    and, in an observed column, Table 1's network trained on exact positions."""
    out = {name: trained_config(cfgs[name], column) for name in NETWORKS}
    if column.noise is not None:
        out["lstm_exact_trained"] = dataclasses.replace(cfgs["lstm_exact_trained"], dims="z")
    return out


def plan(runners: dict[bool, Any], cfgs: dict[str, TrainConfig], cols: list[Column],
         seeds: tuple[int, ...]) -> list[tuple[Any, list[TrainConfig], bool]]:
    """Every network run of the table, as ``Runner.prefetch`` takes them: ``runners`` maps air on / off to the
    runner on that data."""
    return [(runners[c.air], [dataclasses.replace(cfg, seed=s) for cfg in network_configs(cfgs, c).values()
                              for s in seeds], True) for c in cols]


def _z_only(x: np.ndarray) -> np.ndarray:
    """(n, T, 3) with x = y = 0: what the one-feature rules and the baseline of one camera see."""
    out = np.zeros_like(x)
    out[..., 2] = x[..., 2]
    return out


@dataclass
class Cell:
    """One learner in one column: which test throws each of its seeds got right."""

    learner: str
    column: Column
    correct: np.ndarray
    """(S, n) bool: seed s got test throw i right (S = 1 for a learner without a seed)."""
    failed: int = 0
    """Seeds that failed to train."""
    val: float | None = None
    """Mean validation accuracy over the seeds (observed as in training), for the networks."""
    feature: str = ""
    """The rule's feature, for the rule."""

    @property
    def interval(self) -> Interval:
        return bootstrap_accuracy(self.correct)


def column_cells(runner: Any, cfgs: dict[str, TrainConfig], column: Column, seeds: tuple[int, ...],
                 contact_height: float) -> list[Cell]:
    """Every learner of :data:`LEARNERS` trained and tested on ``column``, with ``runner`` on the column's data
    (air on or off): ``cfgs`` maps each network of :data:`NETWORKS`, and 'lstm_exact_trained', to its config."""
    ds: Dataset = runner.dataset
    T = cfgs["lstm_positions"].n_frames(ds.fps)
    y = np.asarray(ds.test.y)
    x_train, x_test = column.inputs(ds, T)
    out = []
    for name, cfg in network_configs(cfgs, column).items():
        rows = runner.train_runs(cfg, ("z",), seeds, desc=f"{column.key} {name}")
        models = runner.models(cfg, seeds, dims="z")
        correct = np.stack([m.predict_proba(x_test).argmax(1) == y for m in models])
        out.append(Cell(name, column, correct, failed=sum(r["failed"] for r in rows),
                        val=float(np.mean([r["val_accuracy"] for r in rows]))))
    rocket_train = None if column.noise is None else x_train  # None: the cached fit on the exact split
    labels = [runner.rocket("z", T, s, {"test": x_test}, train_x=rocket_train)["test"] for s in seeds]
    out.append(Cell("minirocket", column, np.stack([p == y for p in labels])))
    observed = dataclasses.replace(ds, train=Split(x_train, ds.train.y, ds.train.params))
    phys = baseline.fit(observed, "z", T / ds.fps)
    out.append(Cell("physics", column, (phys.predict_proba(x_test).argmax(1) == y)[None]))
    rules = cues.rules(_z_only(x_train), ds.train.y, _z_only(x_test), y, ds.fps, contact_height, names=RULE_FEATURES)
    best = max(rules, key=lambda r: r["train_accuracy"])  # chosen on the training split
    out.append(Cell("rule", column, best["correct"][None], feature=best["feature"]))
    out.sort(key=lambda c: LEARNERS.index(c.learner))
    return out


def column_ceiling(cfg: Any, column: Column) -> float:
    """The exact ceiling of a column (``study.experiments.ceiling``): with air, told the mass (which drag makes
    visible) as well as the restitution and friction; without, the restitution and friction."""
    names = ("restitution", "friction", "mass") if column.air else ("restitution", "friction")
    return ceiling.exact_ceiling(cfg, names)


def best_of(cells: list[Cell]) -> dict[str, Any]:
    """The learner with the highest mean accuracy in one column, and whether it is tied with the next: the paired
    difference's interval (same test throws) spans 0."""
    ranked = sorted(cells, key=lambda c: -c.correct.mean())
    first, second = ranked[0], ranked[1]
    diff = bootstrap_difference(first.correct, second.correct)
    return {"best": first.learner, "next": second.learner, "difference": diff, "tied": diff.lo <= 0 <= diff.hi}
