"""The record of one simulated throw, step by step: what the physics checks measure in either engine."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Trace:
    """Every step of one simulated throw (SI units)."""

    t: np.ndarray
    """(N,) seconds."""
    pos: np.ndarray
    """(N, 3) centre position, metres."""
    speed: np.ndarray
    """(N,) centre speed, m/s."""
    in_contact: np.ndarray
    """(N,) bool: at least one contact with the ground."""
    depth: np.ndarray
    """(N,) deepest penetration into the ground, metres (0 when not touching)."""
    energy: np.ndarray
    """(N,) mechanical energy m g z + translational + rotational kinetic, joules."""

    def flight_energies(self, min_steps: int = 20) -> np.ndarray:
        """Mean mechanical energy of each flight phase (a run of >= ``min_steps`` steps without contact), J."""
        out, start = [], None
        free = ~self.in_contact
        for i, f in enumerate(np.append(free, False)):
            if f and start is None:
                start = i
            elif not f and start is not None:
                if i - start >= min_steps:
                    out.append(float(self.energy[start:i].mean()))
                start = None
        return np.array(out)
