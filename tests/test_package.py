"""The package as a whole: its layout, the code keys every cache is named by, and the README's own example."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import study
from study.core import cache

REPO = Path(__file__).resolve().parents[1]


def test_a_change_inside_a_subpackage_changes_the_code_keys(tmp_path):
    copy = tmp_path / "study"
    shutil.copytree(cache.PACKAGE_DIR, copy, ignore=shutil.ignore_patterns("__pycache__"))
    assert cache.source_hash(root=copy) == cache.source_hash()
    assert "simulate/synth.py" in cache.source_files(copy) and "learn/peephole.cpp" in cache.source_files(copy)
    before_all = cache.source_hash(root=copy)
    before_synth = cache.source_hash("simulate.synth", root=copy)
    before_loop = cache.source_hash("learn/peephole.cpp", root=copy)
    with (copy / "simulate" / "synth.py").open("a") as f:
        f.write("\n# an edit\n")
    (copy / "learn" / "peephole.cpp").write_text((copy / "learn" / "peephole.cpp").read_text() + "\n// an edit\n")
    assert cache.source_hash(root=copy) != before_all
    assert cache.source_hash("simulate.synth", root=copy) != before_synth
    assert cache.source_hash("learn/peephole.cpp", root=copy) != before_loop


def test_the_run_keys_follow_the_training_code():
    from study.learn import train

    names = set(train.SOURCES)
    assert {"learn.model", "learn.train", "learn.config", "learn/peephole.cpp", "learn/gru.cpp"} <= names
    cache.source_hash(*train.SOURCES)  # every name resolves to a file


def test_short_names_are_the_subpackage_modules():
    from study import synth, track, train
    from study.learn import train as train_module
    from study.see import track as track_module
    from study.simulate import synth as synth_module

    assert (synth, train, track) == (synth_module, train_module, track_module)
    with pytest.raises(AttributeError):
        study.no_such_module  # noqa: B018


@pytest.mark.slow  # simulates small datasets and trains for a few epochs
def test_the_readme_python_example_runs_as_written(tmp_path):
    """The README's Python block, as written except that every preset is 'smoke' (the paper's takes an hour)."""
    readme = (REPO / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", readme, flags=re.S)
    assert blocks, "the README has no Python example"
    code = "\n".join(blocks).replace('"/tmp/my-model"', repr(str(tmp_path / "my-model"))).replace('"paper"', '"smoke"')
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (tmp_path / "my-model" / "weights.pt").is_file()
    assert (tmp_path / "data").is_dir()  # the example's cache went where it ran, not into the project
