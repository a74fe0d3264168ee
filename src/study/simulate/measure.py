"""Measurements on trajectories: bounces, time to rest, distance travelled, and one-feature rules.

These work on what a camera gives, centre positions at the frame rate, (T, 3) or (n, T, 3) metres,
and serve both the dataset statistics in the book and the paper's claim that no simple rule
separates the classes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_RISE = 0.02
"""Metres. A bounce is a fall to a low point followed by a rise of at least this much (see :func:`bounces`)."""
REST_SPEED = 0.05
"""Speed (m/s) below which the object counts as at rest, if it stays below for the rest of the record."""


@dataclass(frozen=True)
class Bounces:
    """The bounces of one height series, as frame indices."""

    impacts: np.ndarray
    """(k,) int: the lowest point of each fall that is followed by a rise of at least ``min_rise``."""
    apexes: np.ndarray
    """(j,) int, j <= k: the highest point of each of those rises, once the object has fallen
    ``min_rise`` from it again (a rise still going on when the series ends has no apex yet)."""


def bounces(z: np.ndarray, min_rise: float = MIN_RISE) -> Bounces:
    """The study's one bounce detector, for simulated and tracked heights alike.

    ``z``: (T,) heights, metres (or any unit, with ``min_rise`` in the same). Hysteresis: a *fall* is
    a drop of at least ``min_rise`` below the highest point since the last low; a *bounce* is a rise
    of at least ``min_rise`` above the lowest point of a fall (its *impact*). Wiggles smaller than
    ``min_rise`` -- a box rocking on an edge, a tracker's jitter -- are neither. The launch is no
    impact, so a throw that starts by rising is not a bounce.
    """
    z = np.asarray(z, dtype=float)
    impacts: list[int] = []
    apexes: list[int] = []
    hi, lo, falling = 0, 0, False
    for t in range(1, len(z)):
        if not falling:
            if z[t] > z[hi]:
                hi = t
            elif z[hi] - z[t] >= min_rise:
                if impacts:
                    apexes.append(hi)  # the top of a rebound (the launch's top is no apex)
                falling, lo = True, t
        elif z[t] < z[lo]:
            lo = t
        elif z[t] - z[lo] >= min_rise:
            impacts.append(lo)
            falling, hi = False, t
    return Bounces(np.asarray(impacts, dtype=np.int64), np.asarray(apexes, dtype=np.int64))


def bounce_count(z: np.ndarray, min_rise: float = MIN_RISE) -> np.ndarray | int:
    """Number of bounces (:func:`bounces`) in each height series: ``z`` (T,) -> int, (n, T) -> (n,) int64."""
    z = np.asarray(z, dtype=float)
    counts = np.array([len(bounces(s, min_rise).impacts) for s in np.atleast_2d(z)], dtype=np.int64)
    return int(counts[0]) if z.ndim == 1 else counts


def first_contact(z: np.ndarray) -> int | None:
    """Frame at which the first fall ends (the first local minimum of ``z`` (T,)), or None if z never turns."""
    dz = np.diff(np.asarray(z, dtype=float))
    lows = np.flatnonzero((dz[:-1] < 0) & (dz[1:] >= 0)) + 1
    return int(lows[0]) if len(lows) else None


def speeds(x: np.ndarray, fps: float) -> np.ndarray:
    """Centre speed between frames, m/s: (n, T-1) from (n, T, 3)."""
    return np.linalg.norm(np.diff(np.asarray(x, dtype=float), axis=-2), axis=-1) * fps


def time_to_rest(x: np.ndarray, fps: float, rest_speed: float = REST_SPEED) -> np.ndarray:
    """Seconds until the speed drops below ``rest_speed`` for good: (n,) from (n, T, 3).

    An object still moving at the end of the record gets the record's length (a lower bound).
    """
    v = speeds(x, fps)
    moving = v >= rest_speed
    T = v.shape[-1]
    last = np.where(moving.any(axis=-1), T - 1 - np.argmax(moving[..., ::-1], axis=-1), -1)
    return (last + 1) / fps


def horizontal_distance(x: np.ndarray) -> np.ndarray:
    """Distance in the ground plane from the first to the last frame, metres: (n,) from (n, T, 3)."""
    x = np.asarray(x, dtype=float)
    return np.linalg.norm(x[..., -1, :2] - x[..., 0, :2], axis=-1)


def fall_acceleration(z: np.ndarray, fps: float, contact_height: float) -> np.ndarray:
    """Vertical acceleration of the first free flight, m/s^2: (n,) from heights ``z`` (n, T) metres.

    The flight is every frame before the centre first comes within ``contact_height`` of the ground
    (the shape's bounding radius: no point of the object can touch the ground before that), a parabola
    fitted to it by least squares, its second derivative returned (about -g, less so for an object that
    the air slows). NaN where fewer than four frames precede the first possible contact.
    """
    z = np.atleast_2d(np.asarray(z, dtype=float))
    out = np.full(len(z), np.nan)
    t = np.arange(z.shape[1]) / fps
    for i, s in enumerate(z):
        low = np.flatnonzero(s <= contact_height)
        end = int(low[0]) if len(low) else len(s)
        if end >= 4:
            out[i] = 2 * np.polyfit(t[:end], s[:end], 2)[0]
    return out


def best_threshold_rule(f_train: np.ndarray, y_train: np.ndarray, f_test: np.ndarray, y_test: np.ndarray) -> dict:
    """The best one-feature rule ``label = [f > t]`` or ``[f <= t]``, chosen on train, scored on test.

    A value that could not be measured (NaN) counts as the training split's median.

    Returns threshold, direction ('>' predicts heavy above t, '<=' below), train and test accuracy,
    ``heavy``: (n_test,) bool, which test items the rule calls heavy, and ``correct``: (n_test,) bool, which it gets
    right.
    """
    f_train, f_test = np.asarray(f_train, float), np.asarray(f_test, float)
    fill = np.nanmedian(f_train) if np.isfinite(f_train).any() else 0.0  # a feature that cannot be measured
    f_train, f_test = np.where(np.isfinite(f_train), f_train, fill), np.where(np.isfinite(f_test), f_test, fill)
    cands = np.unique(f_train)
    cands = np.concatenate([[cands[0] - 1.0], (cands[:-1] + cands[1:]) / 2, [cands[-1] + 1.0]])
    best = (-1.0, 0.0, ">")
    for t in cands:
        for direction in (">", "<="):
            pred = f_train > t if direction == ">" else f_train <= t
            acc = float(np.mean(pred == (y_train == 1)))
            if acc > best[0]:
                best = (acc, float(t), direction)
    acc, t, direction = best
    pred = f_test > t if direction == ">" else f_test <= t
    correct = pred == (np.asarray(y_test) == 1)
    return {"threshold": t, "direction": direction, "train_accuracy": acc, "test_accuracy": float(np.mean(correct)),
            "heavy": pred, "correct": correct}


def best_rule(rules: list[dict]) -> dict:
    """Of several :func:`best_threshold_rule` results (one per feature, :func:`simple_rules`), the one with the
    highest *training* accuracy (ties: the first): the one place the book chooses its best one-feature rule,
    never by its test accuracy."""
    if not rules:
        raise ValueError("best_rule: no rules to choose from")
    return max(rules, key=lambda r: r["train_accuracy"])


FEATURES = {
    "bounces": "number of bounces (rises of 2 cm or more after a fall)",
    "time_to_rest": "time until the object stops, s",
    "distance": "distance travelled in the ground plane, m",
    "max_height_after_1s": "highest point after the first second, m",
    "fall_acceleration": "vertical acceleration of the first fall, m/s²",
}
"""The one-number summaries a simple rule could threshold, with their meaning and unit."""


def features(x: np.ndarray, fps: float, contact_height: float = 0.18) -> dict[str, np.ndarray]:
    """Each of :data:`FEATURES` for every trajectory of ``x`` (n, T, 3) metres: name -> (n,) array.

    ``contact_height``: the shape's bounding radius, for :func:`fall_acceleration` (a 20 cm cube's, 0.173
    m, rounded up).
    """
    x = np.asarray(x, dtype=float)
    after = x[:, int(round(fps)) :, 2]
    return {
        "bounces": bounce_count(x[:, :, 2]).astype(float),
        "time_to_rest": time_to_rest(x, fps),
        "distance": horizontal_distance(x),
        "max_height_after_1s": after.max(axis=1) if after.shape[1] else x[:, -1, 2],
        "fall_acceleration": fall_acceleration(x[:, :, 2], fps, contact_height),
    }


def simple_rules(x_train: np.ndarray, y_train: np.ndarray, x_test: np.ndarray, y_test: np.ndarray, fps: float,
                 contact_height: float = 0.18, names: tuple[str, ...] | None = None) -> list[dict]:
    """:func:`best_threshold_rule` for every feature of :data:`FEATURES` (or ``names``): one row per feature."""
    f_train, f_test = features(x_train, fps, contact_height), features(x_test, fps, contact_height)
    return [{"feature": name, **best_threshold_rule(f_train[name], y_train, f_test[name], y_test)}
            for name in (names or tuple(FEATURES))]
