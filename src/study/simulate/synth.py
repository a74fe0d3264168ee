"""Data sets of simulated throws: light (bouncy) and heavy (sliding) objects thrown onto the ground, simulated by
MuJoCo (the study's engine) or Bullet (the paper's), cached by content.

The paper (Sec. "Data") animated a launch in Blender over seven key-frames and recorded the object's world
position once the physics engine took over. We set that take-over state directly: a random height, random Euler
angles, random linear and angular velocity; recording starts at that instant (``study.simulate.config``: the
priors, the config, the sampling). This module chooses the engine, in one place (:data:`ENGINE_MODULES`): a data
set's key hashes that engine's code (its import closure, ``study.core.cache.code_hash``) and this module's, so an
edit to Bullet's code never re-simulates MuJoCo's data sets, nor the other way round.

The names of ``study.simulate.config`` and of the MuJoCo engine (``study.simulate.mujoco_sim``: ``simulate``,
``initial_data``, ...) are re-exported here, so ``from study import synth`` reaches everything a user needs.
"""

from __future__ import annotations

import dataclasses
import importlib
from pathlib import Path
from types import ModuleType

import numpy as np

from study import __version__
from study.core import cache, datadir
from study.core.errors import ConfigError
from study.simulate import data
from study.simulate.config import (  # noqa: F401  (re-exported: synth.SynthConfig and friends)
    ENGINES,
    GRAVITY,
    HEAVY,
    LIGHT,
    LIGHT_BALLS,
    SLEEP_STEPS,
    ClassPrior,
    Engine,
    LaunchPrior,
    SynthConfig,
    json_roundtrip,
    max_sleep_tolerance,
    sample_launch,
    sample_objects,
    sample_split,
    staggered_qvel,
)
from study.simulate.mujoco_sim import (  # noqa: F401  (re-exported: the study's engine)
    build_model,
    initial_data,
    simulate,
    simulate_reference,
    step_states,
)

ENGINE_MODULES: dict[str, str] = {"mujoco": "study.simulate.mujoco_sim", "bullet": "study.simulate.bullet"}
"""Each engine's module: ``check_restitutions(cfg)``, ``versions()`` and ``simulate_split(cfg, params, threads,
progress, desc)``. Imported when a data set of that engine is asked for (pybullet loads only then)."""


def engine(name: str) -> ModuleType:
    """The module of the engine ``name`` (:data:`ENGINE_MODULES`)."""
    if name not in ENGINE_MODULES:
        raise ConfigError(f"engine {name!r} is unknown; use one of {', '.join(ENGINE_MODULES)}")
    return importlib.import_module(ENGINE_MODULES[name])


def provenance(name: Engine = "mujoco") -> dict[str, str]:
    """What can change the numbers an engine simulates: its code (the import closure of its module, and this
    module's own source) and its libraries' versions."""
    return {"study": __version__, "code": cache.code_hash(f"dataset-{name}"), **engine(name).versions()}


def cache_key(cfg: SynthConfig, seed: int) -> str:
    """Content key of the dataset ``(cfg, seed)`` makes: config, seed, its engine's code and library versions."""
    return cache.key({"config": cfg.to_dict(), "seed": seed, **provenance(cfg.engine)})


def generate(cfg: SynthConfig, seed: int = 0, *, threads: int | None = None, progress: bool = True) -> data.Dataset:
    """Simulate the dataset ``(cfg, seed)`` in memory (no cache). See :func:`dataset` for the cached one."""
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise ConfigError(f"seed = {seed!r} must be a non-negative integer")
    cfg.validate()
    sim = engine(cfg.engine)
    sim.check_restitutions(cfg)
    splits = {}
    for name in data.SPLITS:
        params = sample_split(cfg, seed, name)
        x = sim.simulate_split(cfg, params, threads, progress, f"simulating {name}")
        if not np.all(np.isfinite(x)):
            raise RuntimeError("simulation produced non-finite positions")  # a bug, not bad input
        label = params.pop("label")
        splits[name] = data.Split(x=x.astype(np.float32), y=label, params=params)
    meta = {"key": cache_key(cfg, seed), "config": cfg.to_dict(), "seed": seed, "versions": provenance(cfg.engine)}
    return data.Dataset(train=splits["train"], test=splits["test"], fps=cfg.fps, meta=meta)


def default_path(cfg: SynthConfig, seed: int, data_dir: str | Path | None = None) -> Path:
    """Where :func:`dataset` keeps ``(cfg, seed)``: ``<data_dir>/synth-<key>.npz`` (None: the cache folder,
    ``study.core.datadir``)."""
    return datadir.resolve(data_dir) / f"synth-{cache_key(cfg, seed)}.npz"


def load(path: str | Path) -> data.Dataset:
    """Read a dataset file and check that its header's config, seed and key agree with each other."""
    ds = data.load(path)
    meta = ds.meta
    try:
        cfg = SynthConfig.from_dict(meta["config"])
        key = cache.key({"config": meta["config"], "seed": meta["seed"], **meta["versions"]})  # as written
    except (KeyError, ConfigError) as e:
        raise data.DataError(f"dataset {path}: the header lacks a valid config ({e}); regenerate it with `study synth`") from None
    if key != meta.get("key"):
        raise data.DataError(f"dataset {path}: its config and seed do not match its key (edited?); regenerate it with `study synth`")
    if ds.n_frames != cfg.n_frames or len(ds.train) != 2 * cfg.n_train or len(ds.test) != 2 * cfg.n_test:
        raise data.DataError(f"dataset {path}: array sizes disagree with its config; regenerate it with `study synth`")
    return ds


def dataset(
    cfg: SynthConfig | str,
    seed: int = 0,
    *,
    data_dir: str | Path | None = None,
    threads: int | None = None,
    progress: bool = True,
) -> data.Dataset:
    """The dataset ``(cfg, seed)``: read from ``data_dir`` (None: the cache folder, ``study.core.datadir``) if
    present and valid, else simulated and saved.

    ``cfg`` may be a preset name. A cached file from other code or library versions has another key,
    so it is never mistaken for this one; a corrupt one is replaced.
    Example::

        ds = study.dataset("smoke", seed=0)      # simulated once, then read from data/
        x, y = ds.train.x, ds.train.y            # (n, T, 3) float32 metres; (n,) 0 light, 1 heavy
    """
    if isinstance(cfg, str):
        cfg = SynthConfig.preset(cfg)
    path = default_path(cfg, seed, data_dir)
    with cache.one_maker(path):  # another chapter simulating the same throws: wait for it, then read them
        if path.exists():
            try:
                return load(path)
            except data.DataError:
                pass  # corrupt or truncated: simulate again and replace it
        ds = generate(cfg, seed, threads=threads, progress=progress)
        data.save(ds, path)
    return dataclasses.replace(ds, path=path)


def generate_to_file(
    cfg: SynthConfig,
    seed: int = 0,
    *,
    out: str | Path | None = None,
    data_dir: str | Path | None = None,
    threads: int | None = None,
    progress: bool = True,
) -> Path:
    """Make sure the dataset ``(cfg, seed)`` exists as a file and return its path (``out`` if given)."""
    if out is None:
        return dataset(cfg, seed, data_dir=data_dir, threads=threads, progress=progress).path  # type: ignore[return-value]
    ds = generate(cfg, seed, threads=threads, progress=progress)
    return data.save(ds, out)
