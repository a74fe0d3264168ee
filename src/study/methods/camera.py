"""The camera conditions the motion, engine and decision chapters train and test under: the air on or off,
and the positions exact or observed by a camera (one pixel at 4 m, the calibrated tracker, one pixel at 55 m).

A :class:`Column` is one condition; :func:`columns` gives the eight of the motion chapter's table;
:meth:`Column.inputs` draws a condition's observed inputs (the same draw for every learner and engine), and
:func:`trained_config` trains a network on it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import get_args

import numpy as np

from study.learn.config import TrainConfig
from study.learn.inputs import observe_fields
from study.methods import ceiling
from study.methods.tracker import TrackerError
from study.report.motion import Air, View
from study.simulate import observe
from study.simulate.data import Dataset
from study.simulate.synth import SynthConfig

AIRS: tuple[Air, ...] = get_args(Air)
VIEWS: tuple[View, ...] = get_args(View)
SHORT: dict[View, str] = {"exact": "exact", "near": "1 px at 4 m", "calibrated": "tracker", "far": "1 px at 55 m"}
"""Each view in a table's header."""


ROWS_1080 = 1080
"""Image rows of the camera whose pixel sets the two ends of the noise sweep."""
NEAR, FAR = 4.0, 55.0
"""Camera distances, metres: as the rendered videos are filmed, and where one pixel is about 4 cm."""
RULE_FEATURES = ("bounces", "max_height_after_1s", "fall_acceleration")
"""The one-feature rules a height alone allows (``study.simulate.measure.FEATURES``)."""
AIR_OFF_PARAMETERS = ("restitution", "friction")
"""What the Bayes rule is told without air: all a trajectory can carry of the class."""
AIR_ON_PARAMETERS = ("restitution", "friction", "mass")
"""With air, the mass too: drag makes it visible."""


@dataclass(frozen=True)
class Column:
    """One condition of the table: the air, and the camera's error (None: exact positions)."""

    air: bool
    """Air drag and added mass on (the study's data) or off (the same throws without air)."""
    name: View
    """How the positions are seen."""
    noise: float | None
    """The camera and tracker's position error, metres (with a tracker model, its standard deviation in flight,
    offset included); None for exact positions."""
    drop: float = 0.0
    """The share of frames the tracker loses."""
    label: str = ""
    """What the column is, in words, for the table's header and caption."""
    tracker: observe.TrackerNoise | None = None
    """The tracker's error model the column draws from; None: white noise of ``noise``."""

    @property
    def air_key(self) -> Air:
        return "air_on" if self.air else "air_off"

    @property
    def key(self) -> str:
        """``air_on.exact`` and so on: the column's part of a result's name."""
        return f"{self.air_key}.{self.name}"

    @property
    def heading(self) -> str:
        """The column in a table's header: ``air on, 1 px at 4 m``."""
        return f"{'air on' if self.air else 'air off'}, {SHORT[self.name]}"

    def observation(self) -> observe.Observation | None:
        """How the column observes a throw (None: exactly)."""
        if self.noise is None:
            return None
        if self.tracker is not None:
            return observe.Observation(tracker=self.tracker, drop=self.drop)
        return observe.Observation(noise=self.noise, drop=self.drop)

    def inputs(self, ds: Dataset, T: int) -> tuple[np.ndarray, np.ndarray]:
        """(training, test) inputs of ``ds``'s first ``T`` frames, (n, T, 3) metres: exact, or observed with
        the column's error. Each column draws its own noise, the same for every learner and every engine (the
        seed depends on the column alone), the training split's apart from the test split's."""
        ob = self.observation()
        if ob is None:
            return ds.train.x[:, :T], ds.test.x[:, :T]
        salt = 100 * (2 if self.air else 3) + VIEWS.index(self.name)
        return ob.observe(ds.train.x[:, :T], ds.fps, seed=salt + 50), ob.observe(ds.test.x[:, :T], ds.fps, seed=salt)


def columns(calibrated: observe.Observation | TrackerError) -> list[Column]:
    """The table's eight columns: air on and off, each exact, white noise of one pixel of a 1080-row camera at
    :data:`NEAR` m, the calibrated tracker (``calibration.observation``: its fitted error model, or the white noise a
    ``TrackerError`` gives), and white noise of one pixel at :data:`FAR` m, every observed one losing the
    calibrated share of frames."""
    ob = calibrated if isinstance(calibrated, observe.Observation) else calibrated.observation()
    near = observe.Camera(distance=NEAR, rows=ROWS_1080).metres_per_pixel()
    far = observe.Camera(distance=FAR, rows=ROWS_1080).metres_per_pixel()
    if ob.tracker is not None:
        tracked = (ob.tracker.position_sd(), f"the calibrated tracker's fitted error ({ob.tracker.describe()})")
    else:
        tracked = (ob.noise, f"the calibrated tracker, white noise of {1000 * ob.noise:.1f} mm")
    views: list[tuple[View, float | None, str]] = [
        ("exact", None, "exact positions"),
        ("near", near, f"1 px of a {ROWS_1080}-row camera at {NEAR:g} m ({1000 * near:.1f} mm)"),
        ("calibrated", *tracked),
        ("far", far, f"1 px of a {ROWS_1080}-row camera at {FAR:g} m ({1000 * far:.1f} mm)")]
    return [Column(air, name, noise, 0.0 if noise is None else ob.drop, label,
                   ob.tracker if name == "calibrated" else None)
            for air in (True, False) for name, noise, label in views]


def column_ceiling(cfg: SynthConfig, column: Column) -> float:
    """The exact ceiling of a column (``study.methods.ceiling``): with air, told the mass (which drag makes
    visible) as well as the restitution and friction; without, the restitution and friction."""
    return ceiling.exact_ceiling(cfg, AIR_ON_PARAMETERS if column.air else AIR_OFF_PARAMETERS)


def trained_config(cfg: TrainConfig, column: Column) -> TrainConfig:
    """``cfg`` trained on the column's condition: exact, or observed with its noise and lost frames."""
    ob = column.observation()
    if ob is None:
        return dataclasses.replace(cfg, dims="z")
    return dataclasses.replace(cfg, dims="z", observe="fixed", **observe_fields(ob))


