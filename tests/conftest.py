"""Shared fixtures: the smoke dataset, simulated once per test session into a temporary cache."""

import os

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")


@pytest.fixture(scope="session")
def smoke_cfg():
    from study import synth

    return synth.SynthConfig.preset("smoke")


@pytest.fixture(scope="session")
def smoke_dataset(tmp_path_factory, smoke_cfg):
    from study import synth

    return synth.dataset(smoke_cfg, seed=0, data_dir=tmp_path_factory.mktemp("data"), progress=False)
