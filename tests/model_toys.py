"""Tiny synthetic datasets for the model tests: bouncing balls, light (e = 0.8) vs heavy (e = 0.3)."""

from __future__ import annotations

import numpy as np

from study.simulate import data


def bounces(n: int, T: int, seed: int = 0, fps: float = 30.0) -> tuple[np.ndarray, np.ndarray]:
    """(n, T, 3) float32 metres and (n,) int64 labels; even indices light, odd heavy."""
    rng = np.random.default_rng(seed)
    y = (np.arange(n) % 2).astype(np.int64)
    e = np.where(y == 0, 0.8, 0.3) + rng.uniform(-0.05, 0.05, n)
    mu = np.where(y == 0, 0.5, 2.0)  # horizontal deceleration, m/s^2
    dt, r, g = 1 / fps, 0.05, 9.81
    x = np.zeros((n, T, 3))
    pos = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(0.5, 1.5, n)])
    vel = np.column_stack([rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), rng.uniform(-1, 1, n)])
    for t in range(T):
        x[:, t] = pos
        vel[:, 2] -= g * dt
        speed = np.linalg.norm(vel[:, :2], axis=1, keepdims=True)
        vel[:, :2] *= np.clip(1 - mu[:, None] * dt / np.maximum(speed, 1e-9), 0, 1)
        pos = pos + vel * dt
        hit = pos[:, 2] < r
        pos[hit, 2] = r
        vel[hit, 2] = np.where(-vel[hit, 2] * e[hit] > 0.2, -vel[hit, 2] * e[hit], 0.0)
    return x.astype(np.float32), y


def dataset(n: int = 32, T: int = 30, seed: int = 0, key: str = "toy") -> data.Dataset:
    """Train and test splits of ``n`` trajectories of ``T`` frames at 30 fps."""
    xtr, ytr = bounces(n, T, seed)
    xte, yte = bounces(n, T, seed + 1000)
    return data.Dataset(train=data.Split(xtr, ytr), test=data.Split(xte, yte), fps=30.0, meta={"key": key})
