"""Shared fixtures (the smoke dataset, simulated once per test session into a temporary cache) and the rule
that makes `pytest -m "not slow"` a quick unit run: a test that uses a fixture which renders video, trains
a model or executes a notebook is marked slow here; a test that does so itself carries the mark."""

import os
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")


@pytest.fixture(scope="session")
def smoke_cfg():
    from study.simulate import synth

    return synth.SynthConfig.preset("smoke")


@pytest.fixture(scope="session")
def smoke_dataset(tmp_path_factory, smoke_cfg):
    from study.simulate import synth

    return synth.dataset(smoke_cfg, seed=0, data_dir=tmp_path_factory.mktemp("data"), progress=False)


SLOW_FIXTURES = {"rendered", "rendered_set", "small_video", "tm", "z_model", "tiny", "bad_book"}
"""Fixtures that render video, train a model or run notebook kernels."""


def pytest_collection_modifyitems(items):
    for item in items:
        if SLOW_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)


PROJECT_DATA = Path(__file__).resolve().parents[1] / "data"


def _listing(folder: Path) -> dict[str, int]:
    return {str(f.relative_to(folder)): f.stat().st_mtime_ns for f in folder.rglob("*") if f.is_file()} if folder.is_dir() else {}


@pytest.fixture(scope="session", autouse=True)
def tests_leave_the_project_data_alone():
    """Tests write only to temporary folders: the project's own data/ is the same after the session."""
    before = _listing(PROJECT_DATA)
    yield
    assert _listing(PROJECT_DATA) == before, "a test wrote into the project's data/ folder; use tmp_path"
