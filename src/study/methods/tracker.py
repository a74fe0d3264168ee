"""The tracker's error, measured on rendered video whose true positions are known: what a camera and the colour tracker
deliver of a throw's height, decomposed, before and after issue 28's tracker.

- :func:`track_rendered`: a rendered throw tracked end to end as the book tracks it: its heights from the render's
  camera (``study.see.render.scene_camera``: its position, tilt and focal length) at the object's depth along the
  view axis, which the render knows frame by frame, as a range sensor beside a car's camera would (a single camera
  cannot: the depth-free pipeline, one scale from the object's size at rest, is measured too, :attr:`Decomposition
  .scale_rms_mm`);
- :func:`decompose`: the height error frame by frame against the truth, taken apart as the observation model needs
  it (:class:`Decomposition`: bias, per-throw offset, noise with its frame-to-frame autocorrelation, levels in
  flight and in contact, the error of the frame-to-frame velocity, the end-to-end height error with and without
  each video's median, lost frames while the object is in view);
- :func:`measure`: the :class:`TrackerError` observed runs' white noise is sized by (the image row's error), with
  lost frames counted only while the object is in the picture;
- :data:`TRACKERS`: the tracker with the orange preset's old bounds and a plain centroid, and as it is now.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from study.methods.videos import Video
from study.see import render, track
from study.see.config import TrackConfig
from study.see.trajectory import Trajectory
from study.simulate import observe

DEPTH = 4.0
"""The rendered camera's distance to the throw, metres (where a pixel's size is taken)."""
TRACKERS: dict[str, TrackConfig] = {
    "before": TrackConfig(hsv=(3, 120, 80, 20, 255, 255), centroid="binary", progress=False),
    "after": TrackConfig(color="orange", progress=False),
}
"""The tracker of the rendered throws before issue 28 (the orange preset's old lower bounds S 120, V 80, which drop
the box's shaded faces, and a plain centroid) and after (the preset's bounds now, a saturation-weighted centroid)."""
LABELS: dict[str, str] = {"before": "old bounds (S ≥ 120, V ≥ 80), plain centroid",
                          "after": "bounds S ≥ 100, V ≥ 25, weighted centroid"}
"""Each of :data:`TRACKERS` as a table's column names it."""


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
    """Share of the frames in view (the true centre inside the picture) the tracker lost, in [0, 1]."""
    n_frames: int
    """Frames the tracker measured, over every video."""
    metres_per_pixel: float
    """Size of one pixel at the camera's distance, metres."""

    def observation(self) -> observe.Observation:
        """White noise of this size and this share of lost frames (the reference the fitted model is set beside)."""
        return observe.Observation(noise=self.noise_m, drop=self.drop)

    def to_json(self) -> dict[str, Any]:
        """Its fields as JSON-able values (the runner's cache file)."""
        return asdict(self)

    @classmethod
    def from_json(cls, stored: Mapping[str, Any]) -> TrackerError:
        """The error of a cache file written by :meth:`to_json`."""
        return cls(float(stored["noise_px"]), float(stored["noise_m"]), float(stored["drop"]),
                   int(stored["n_frames"]), float(stored["metres_per_pixel"]))


def in_view(truth: Mapping[str, np.ndarray], width: int, height: int) -> np.ndarray:
    """(n,) bool: the frames whose true centre projects inside a ``width`` x ``height`` picture."""
    return (truth["u"] >= 0) & (truth["u"] < width) & (truth["v"] >= 0) & (truth["v"] < height)


def camera_of(traj: Trajectory, name: str = "side"):
    """The scene's camera ``name`` at the video's size (``study.see.render.scene_camera``)."""
    return render.scene_camera(render.class_model("light"), name, traj.width, traj.height_px)


def track_rendered(v: Video, cfg: TrackConfig | None = None) -> Trajectory:
    """A rendered throw tracked end to end: detected with ``cfg`` (default its colour's preset), heights from the
    render's camera at the object's true depth frame by frame, above its rest height."""
    if v.truth is None:
        raise ValueError(f"{v.path}: not a rendered video (no ground truth)")
    cfg = cfg or TrackConfig(color=v.color, progress=False)
    truth = render.read_truth(v.truth)
    traj = track.track_video(v.path, cfg, object_size=v.object_size)  # detected, filled, smoothed
    cam = camera_of(traj)
    depth = cam.depth_of(np.stack([truth["x"], truth["y"], truth["z"]], axis=1))
    return track.set_camera(traj, cam, depth, v.rest_height)


@dataclass(frozen=True)
class Decomposition:
    """The tracked height's error against the truth on a set of rendered videos, taken apart (millimetres unless
    said otherwise)."""

    bias_mm: float
    """Mean error over every measured frame (tracked minus true; up positive)."""
    offset_mm: float
    """Spread of the videos' mean errors: a per-throw offset."""
    noise_mm: float
    """Standard deviation of the error about each video's mean, pooled."""
    rho: float
    """Lag-1 autocorrelation of that error from frame to frame (0 for white noise)."""
    flight_mm: float
    """Its standard deviation while the object flies."""
    contact_mm: float
    """...and while it touches the ground (``study.simulate.observe.in_contact`` on the true heights)."""
    velocity_mps: float
    """Root mean square error of the frame-to-frame velocity (consecutive measured frames), metres per second."""
    white_velocity_mps: float
    """What white noise of the same size (:attr:`noise_mm`) would give that velocity error: it overstates (or
    understates) the tracker's by :attr:`velocity_ratio`."""
    height_rms_mm: float
    """End-to-end height error, root mean square, over every measured frame."""
    height_rms_median_mm: float
    """The same with each video's median error removed (as the calibration does)."""
    scale_rms_median_mm: float
    """The depth-free pipeline's height error (one scale from the object's size at rest), median removed."""
    lost: float
    """Share of the frames in view the tracker lost."""
    n_frames: int
    """Frames measured, every video."""
    n_videos: int

    @property
    def velocity_ratio(self) -> float:
        return self.white_velocity_mps / self.velocity_mps if self.velocity_mps else float("nan")


Errors = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""One video's (geometry error, depth-free scale error, true heights, in view), each (n,); errors in metres, NaN where
the tracker measured nothing."""


def _errors(videos: Sequence[Video], cfg: TrackConfig) -> list[Errors]:
    """Per rendered video: (geometry error, scale error, true heights, in view), metres, NaN where not measured."""
    out = []
    for v in videos:
        if v.truth is None:
            continue
        truth = render.read_truth(v.truth)
        traj = track_rendered(v, cfg)
        scaled = track.set_scale(traj, object_size=v.object_size)
        m = traj.measured
        geo = np.where(m, traj.height + v.rest_height - truth["z"], np.nan)
        sc = np.where(m, scaled.height + v.rest_height - truth["z"], np.nan)
        out.append((geo, sc, truth["z"], in_view(truth, traj.width, traj.height_px)))
    return out


def decompose(videos: Sequence[Video], cfg: TrackConfig, fps: float | None = None) -> Decomposition:
    """:class:`Decomposition` of the tracker ``cfg``'s height error on the rendered ``videos`` (``fps``: their frame
    rate, default their truth's)."""
    errs = _errors(videos, cfg)
    if not errs:
        raise ValueError("decompose: no rendered video with ground truth")
    if fps is None:
        t = render.read_truth(next(v for v in videos if v.truth is not None).truth)["t"]
        fps = 1.0 / float(np.median(np.diff(t)))
    return decomposition(errs, fps)


def decomposition(errs: Sequence[Errors], fps: float) -> Decomposition:
    """:class:`Decomposition` of per-video errors (:data:`Errors`) at ``fps`` frames per second."""
    geo = [e[0] for e in errs]
    allv = np.concatenate(geo)
    allv = allv[np.isfinite(allv)]
    means = np.array([np.nanmean(e) for e in geo])
    resid = [e - np.nanmean(e) for e in geo]
    r = np.concatenate(resid)
    contact = np.concatenate([observe.in_contact(e[2]) for e in errs])
    ok = np.isfinite(r)
    num = sum(np.nansum(x[1:] * x[:-1]) for x in resid)
    den = sum(np.nansum((x[1:] ** 2 + x[:-1] ** 2) / 2) for x in resid)
    dv = np.concatenate([np.diff(e) for e in geo]) * fps
    dv = dv[np.isfinite(dv)]
    noise = float(r[ok].std())
    med = np.concatenate([e - np.nanmedian(e) for e in geo])
    sc = np.concatenate([e[1] - np.nanmedian(e[1]) for e in errs])
    seen = np.concatenate([e[3] for e in errs])
    lost = float(np.mean(~np.isfinite(np.concatenate(geo))[seen])) if seen.any() else 0.0
    return Decomposition(
        1000 * float(allv.mean()), 1000 * float(means.std()), 1000 * noise, float(num / den) if den else 0.0,
        1000 * float(r[ok & ~contact].std()), 1000 * float(r[ok & contact].std()) if (ok & contact).any() else 0.0,
        float(np.sqrt(np.mean(dv ** 2))), float(np.sqrt(2) * noise * fps), 1000 * float(np.sqrt(np.mean(allv ** 2))),
        1000 * float(np.sqrt(np.nanmean(med ** 2))), 1000 * float(np.sqrt(np.nanmean(sc ** 2))), lost,
        int(len(allv)), len(errs))


def measure(videos: Sequence[Video], depth: float = DEPTH, cfg: TrackConfig | None = None) -> TrackerError:
    """The tracker's error on the ``videos`` that have ground truth (rendered ones; the others are skipped): each
    video tracked, its tracked image row compared with the true centre's projection, frame by frame; lost frames
    counted while the true centre is in the picture."""
    residuals, lost, seen = [], 0, 0
    for v in videos:
        if v.truth is None:
            continue
        truth = render.read_truth(v.truth)
        traj = track.detect_all(v.path, cfg or TrackConfig(color=v.color, progress=False))
        m = traj.measured
        err = (traj.v - truth["v"])[m]
        residuals.append(err - np.median(err))
        view = in_view(truth, traj.width, traj.height_px)
        lost += int((~m & view).sum())
        seen += int(view.sum())
    r = np.concatenate(residuals)
    mpp = render.metres_per_pixel(render.class_model("light"), "side", 240, depth=depth)
    return TrackerError(float(r.std()), float(r.std() * mpp), lost / max(seen, 1), int(len(r)), mpp)
