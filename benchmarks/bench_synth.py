"""Synthesis speed: the plain Python mj_step loop vs mujoco.rollout on 1 thread and on all cores.

Prints trajectories per second and simulated seconds per wall second for each, and the ratios
against the plain loop, all measured in this run on the same objects (paper config: 10 s throws).
One more row runs the rollout with every object kept awake (``sleep_tolerance=0``), the way
synthesis ran before resting objects were put to sleep; its positions differ after objects stop.

    python benchmarks/bench_synth.py [--n 24] [--duration 10]
"""

from __future__ import annotations

import argparse
import os
import time

from study.simulate import synth


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=24, help="trajectories per run (half light, half heavy)")
    ap.add_argument("--duration", type=float, default=10.0, help="seconds simulated per trajectory")
    a = ap.parse_args()
    cfg = synth.SynthConfig.preset("paper").replace(n_train=a.n // 2, duration=a.duration)
    params = synth.sample_split(cfg, 0, "train")
    cores = os.cpu_count() or 1
    runs = {
        "plain mj_step loop": lambda: synth.simulate_reference(cfg, params),
        "rollout, 1 thread": lambda: synth.simulate(cfg, params, threads=1, progress=False),
        f"rollout, {cores} threads": lambda: synth.simulate(cfg, params, threads=cores, progress=False),
        "rollout, 1 thread, awake": lambda: synth.simulate(cfg.replace(sleep_tolerance=0.0), params, threads=1, progress=False),
    }
    print(f"{a.n} trajectories x {a.duration:g} s at dt = {cfg.timestep:.3g} s ({cfg.steps_per_frame} steps/frame), {cores} cores")
    times, results = {}, {}
    for name, fn in runs.items():
        t0 = time.perf_counter()
        results[name] = fn()
        times[name] = time.perf_counter() - t0
    base = times["plain mj_step loop"]
    ref = results["plain mj_step loop"]
    print(f"{'path':<26}{'traj/s':>10}{'sim s / wall s':>16}{'ratio':>8}  bitwise equal")
    for name, t in times.items():
        same = results[name].tobytes() == ref.tobytes()
        print(f"{name:<26}{a.n / t:>10.2f}{a.n * a.duration / t:>16.1f}{base / t:>7.2f}x  {same}")
    print(f"sleeping vs awake, rollout on 1 thread: {times['rollout, 1 thread, awake'] / times['rollout, 1 thread']:.2f}x")


if __name__ == "__main__":
    main()
