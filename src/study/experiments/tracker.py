"""The tracker's error, measured on rendered video whose true positions are known: the size of the observation
model's noise (``study.simulate.observe``).

The runner measures it once per build and caches it (``Runner.tracker_error``); every chapter that observes
positions "through the calibrated tracker" uses :meth:`TrackerError.observation`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from study.experiments.videos import Video
from study.see import render, track
from study.simulate import observe

DEPTH = 4.0
"""The rendered camera's distance to the throw, metres (where a pixel's size is taken)."""


@dataclass(frozen=True)
class TrackerError:
    """The colour tracker's vertical error and lost frames on rendered video (:func:`measure`)."""

    noise_px: float
    """Standard deviation of the tracked centroid's image row minus the true centre's projection, each video's
    median removed (the constant offset between the centre of the visible faces and the image of the centre),
    pooled over the videos: pixels."""
    noise_m: float
    """The same in metres at the camera's distance (``noise_px * metres_per_pixel``)."""
    drop: float
    """Share of frames the tracker lost while the object was in the picture, in [0, 1]."""
    n_frames: int
    """Frames the tracker measured, over every video."""
    metres_per_pixel: float
    """Size of one pixel at the camera's distance, metres."""

    def observation(self) -> observe.Observation:
        """The calibrated observation: this noise and this share of lost frames."""
        return observe.Observation(noise=self.noise_m, drop=self.drop)

    def to_json(self) -> dict[str, Any]:
        """Its fields as JSON-able values (the runner's cache file)."""
        return asdict(self)

    @classmethod
    def from_json(cls, stored: Mapping[str, Any]) -> TrackerError:
        """The error of a cache file written by :meth:`to_json`."""
        return cls(float(stored["noise_px"]), float(stored["noise_m"]), float(stored["drop"]),
                   int(stored["n_frames"]), float(stored["metres_per_pixel"]))


def measure(videos: Sequence[Video], depth: float = DEPTH) -> TrackerError:
    """The tracker's error on the ``videos`` that have ground truth (rendered ones; the others are skipped):
    each video tracked, its tracked image row compared with the true centre's projection, frame by frame."""
    residuals, lost, seen = [], 0, 0
    for v in videos:
        if v.truth is None:
            continue
        truth = render.read_truth(v.truth)
        traj = track.detect_all(v.path, track.TrackConfig(color=v.color, progress=False))
        m = traj.measured
        err = (traj.v - truth["v"])[m]
        residuals.append(err - np.median(err))
        lost += int((~m).sum())
        seen += len(m)
    r = np.concatenate(residuals)
    mpp = render.metres_per_pixel(render.class_model("light"), "side", 240, depth=depth)
    return TrackerError(float(r.std()), float(r.std() * mpp), lost / max(seen, 1), int(len(r)), mpp)
