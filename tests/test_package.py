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
        f.write("\n_AN_EDIT = 1\n")
    (copy / "learn" / "peephole.cpp").write_text((copy / "learn" / "peephole.cpp").read_text() + "\n// an edit\n")
    assert cache.source_hash(root=copy) != before_all
    assert cache.source_hash("simulate.synth", root=copy) != before_synth
    assert cache.source_hash("learn/peephole.cpp", root=copy) != before_loop


def _copy_package(tmp_path) -> Path:
    copy = tmp_path / "study"
    shutil.copytree(cache.PACKAGE_DIR, copy, ignore=shutil.ignore_patterns("__pycache__"))
    return copy


def _append(copy: Path, rel: str) -> None:
    """An edit of the code: a line of C++ comment (the compiled loops' bytes are hashed) or a Python statement."""
    with (copy / rel).open("a") as f:
        f.write("\n// an edit\n" if rel.endswith((".cpp", ".h")) else "\n_AN_EDIT = 1\n")


def test_a_comment_or_a_docstring_changes_no_key_and_code_does(tmp_path):
    """Keys hash each module's syntax tree without comments and docstrings: rewording retrains nothing."""
    copy = _copy_package(tmp_path)
    rel = "learn/train.py"
    before = {p: cache.code_hash(p, root=copy) for p in cache.PRODUCERS}
    words = cache.source_hash(root=copy, words=True)
    text = (copy / rel).read_text()
    assert text.startswith('"""')
    reworded = '"""Reworded."""\n# a new comment\n' + text.split('"""', 2)[2].replace("\n\n\n", "\n\n\n# spaced\n\n", 1)
    reworded = reworded.replace('    """Score ``tm`` on ``split``', '    """Scores ``tm``, reworded, on ``split``')
    (copy / rel).write_text(reworded)
    assert {p: cache.code_hash(p, root=copy) for p in cache.PRODUCERS} == before
    assert cache.source_hash(root=copy, words=True) != words, "the builder's key of a chapter still sees words"
    (copy / rel).write_text(reworded.replace("return metrics(split.y, pred)", "return metrics(split.y, pred[::-1])"))
    assert cache.code_hash("run", root=copy) != before["run"]


def test_every_key_follows_the_code_its_producer_imports(tmp_path):
    """For every cached product: an edit (a comment appended) to any file of its producer's import closure changes
    its code key; to an exempt module, or to a module outside the closure, it does not."""
    copy = _copy_package(tmp_path)
    for product, (module, extra) in cache.PRODUCERS.items():
        files = sorted(set(cache.closure(module, root=copy)) | set(extra))
        assert module.replace("study.", "").replace(".", "/") + ".py" in files
        for rel in files:
            before = cache.code_hash(product, root=copy)
            _append(copy, rel)
            assert cache.code_hash(product, root=copy) != before, f"{product}: an edit to {rel} leaves its key"
        for rel in cache.EXEMPT:
            before = cache.code_hash(product, root=copy)
            _append(copy, rel)
            assert cache.code_hash(product, root=copy) == before, f"{product}: the exempt {rel} changes its key"


def test_the_run_closure_holds_what_makes_a_record_and_the_engines_stay_apart():
    run = set(cache.closure(cache.PRODUCERS["run"][0]))
    for rel in ("learn/train.py", "learn/stack.py", "learn/model.py", "learn/peephole.py", "learn/gru.py",
                "learn/native.py", "learn/peephole.cpp", "learn/rnn_math.h", "learn/metrics.py", "learn/config.py",
                "simulate/observe.py", "simulate/data.py", "core/cache.py", "runs/records.py"):
        assert rel in run, f"a run's key leaves out {rel}"
    assert "core/errors.py" not in run and "core/progress.py" not in run, "exempt: they cannot change a record"
    mujoco = set(cache.closure(cache.PRODUCERS["dataset-mujoco"][0]))
    bullet = set(cache.closure(cache.PRODUCERS["dataset-bullet"][0]))
    assert "simulate/bullet.py" not in mujoco and "simulate/mujoco_sim.py" not in bullet
    assert {"simulate/config.py", "simulate/contact.py"} <= mujoco & bullet
    assert "simulate/contact.py" in set(cache.closure(cache.PRODUCERS["video"][0])), "a throw's damping"
    for product in ("video", "tracker-error"):
        stray = [f for f in cache.closure(cache.PRODUCERS[product][0]) if f.startswith(("runs/", "learn/", "book/"))]
        assert not stray, f"{product}: training or build code {stray} in a render's key re-renders on every edit to it"


def test_a_function_local_import_is_in_the_closure(tmp_path):
    copy = _copy_package(tmp_path)
    (copy / "core" / "leaf.py").write_text("X = 1\n")
    (copy / "core" / "top.py").write_text("def f():\n    from study.core import leaf\n    return leaf.X\n")
    assert "core/leaf.py" in cache.closure("study.core.top", root=copy)


def test_short_names_are_the_subpackage_modules():
    from study import synth, track, train
    from study.learn import train as train_module
    from study.see import track as track_module
    from study.simulate import synth as synth_module

    assert (synth, train, track) == (synth_module, train_module, track_module)
    with pytest.raises(AttributeError):
        study.no_such_module  # noqa: B018


def _readme_commands(readme: str) -> list[str]:
    """Every command line of the README's bash blocks that the recipes test runs: all but ``make`` and ``study book``
    (the smoke book build runs those), comments dropped."""
    lines = [ln.split("  #")[0].strip() for b in re.findall(r"```bash\n(.*?)```", readme, flags=re.S)
             for ln in b.splitlines()]
    return [ln for ln in lines if ln and not ln.startswith(("make ", "study book"))]


@pytest.mark.slow  # simulates the smoke data set, trains two epochs, renders a throw, executes the data chapter
@pytest.mark.book
def test_every_readme_recipe_runs_as_written(tmp_path):
    """The README's blocks as written, on smoke sizes (every preset 'smoke', the network's budget 2 epochs): the
    Python block as a plain script, then every command line in the same folder, as a reader's would be; each
    answer on a video says how far to trust it."""
    import shlex

    readme = (REPO / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", readme, flags=re.S)
    assert len(blocks) == 1, "the README's Python recipe"
    code = blocks[0].replace('"paper"', '"smoke"').replace("study.TrainConfig(", "study.TrainConfig(epochs=2, ")
    (tmp_path / "recipe.py").write_text(code)  # a plain script, as a reader saves it
    proc = subprocess.run([sys.executable, "recipe.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert re.search(r"accuracy \d+\.\d% \[95 % CI \d+\.\d%, \d+\.\d%\] on \d+ throws", proc.stdout), proc.stdout
    assert all((tmp_path / m / "weights.pt").is_file() for m in ("my-model", "my-video-model"))
    assert (tmp_path / "my-throws.npz").is_file()
    assert (tmp_path / "data").is_dir()  # the recipe's cache went where it ran, not into the project

    (tmp_path / "book").symlink_to(REPO / "book")
    commands = _readme_commands(readme)
    assert len(commands) >= 5 and any(c.startswith("study classify --manifest") for c in commands)
    for line in commands:
        argv = shlex.split(line.replace('"paper"', '"smoke"'))
        exe = Path(sys.executable).parent / Path(argv[0]).name  # `study`, `.venv/bin/papermill`: this environment's
        proc = subprocess.run([str(exe), *argv[1:]], cwd=tmp_path, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, f"{line}: {proc.stderr[-1500:]}"
        if argv[:2] == ["study", "classify"]:
            assert "trust: " in proc.stdout, f"{line}: {proc.stdout}"
            assert ("floor marks" in proc.stdout) == ("--floor" in argv), proc.stdout
    for made in ("throw.csv", "throw-tracked.mp4", "answers.csv", "data-seed3.ipynb", "samples/FLOOR.csv",
                 "samples/MARKS.csv"):
        assert (tmp_path / made).is_file(), made


def test_two_makers_of_one_cache_entry_make_it_once(tmp_path):
    import threading
    import time

    from study.core.cache import one_maker, write_text_atomic

    target, made = tmp_path / "entry.txt", []

    def make(who: str) -> None:
        with one_maker(target):
            if not target.exists():
                time.sleep(0.2)  # the other maker arrives while this one works
                write_text_atomic(target, who)
                made.append(who)

    threads = [threading.Thread(target=make, args=(w,)) for w in ("a", "b")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(made) == 1 and target.read_text() == made[0]


def test_the_public_api_is_every_name_a_user_needs_each_documented_with_an_example():
    names = set(study.__all__)
    assert {"dataset", "fit", "evaluate", "load", "track_video", "classify", "ClassPrior", "TrainConfig"} <= names
    for name in sorted(names - {"CLASSES"}):
        obj = getattr(study, name)
        assert obj.__doc__ and "Example::" in obj.__doc__, f"study.{name} has no example in its docstring"
    namespace: dict = {}
    exec("from study import *", namespace)
    assert names <= set(namespace) and "study.learn.train" == study.fit.__module__
    with pytest.raises(AttributeError, match="no attribute 'fitt'"):
        study.fitt  # noqa: B018


@pytest.mark.slow  # simulates the smoke data set
def test_one_call_trains_without_a_process_pool(tmp_path, monkeypatch):
    import concurrent.futures
    import multiprocessing

    ds = study.dataset("smoke", seed=0, data_dir=tmp_path, progress=False)

    def no_pool(*a, **k):
        raise AssertionError("a process pool was started")

    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", no_pool)
    monkeypatch.setattr(multiprocessing, "Pool", no_pool)
    model = study.fit(ds, study.TrainConfig(length=1.0, epochs=1, hidden=4, truncation=5), progress=False, warn=False)
    assert 0.0 <= study.evaluate(model, ds.test)["accuracy"] <= 1.0
