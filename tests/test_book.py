"""The book pipeline on a tiny two-chapter book: execution, parameter injection, caching, failures, CLI.

One tiny book is executed once per module and then edited by the tests in file order, so
each test pays only for the chapters it makes re-execute (a kernel start, about two seconds).
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

from study import book
from study.cli import main
from study.core.errors import ChapterError, ConfigError

REPO = Path(__file__).resolve().parents[1]

HEADER = """---
jupytext:
  text_representation:
    extension: .md
    format_name: myst
    format_version: 0.13
kernelspec:
  display_name: Python 3
  language: python
  name: python3
---
"""

CONFIG = """title: Tiny
author: tests
only_build_toc_files: true
execute:
  execute_notebooks: "off"
"""

TOC = """format: jb-book
root: book/alpha
chapters:
  - file: book/beta
  - file: book/notes
"""

NOTES = "# Notes\n\nA plain page: no kernel, copied as it is.\n"

# alpha reads the file its parameter names and glues the preset it was given.
ALPHA = HEADER + """
# Alpha

```{code-cell} ipython3
:tags: [parameters]

preset = "paper"
inputs = "inputs.txt"
```

```{code-cell} ipython3
import os

import study
from myst_nb import glue

glue("preset", preset)
glue("content", open(inputs).read().strip())
glue("env", [os.environ.get("PYTHONHASHSEED"), os.environ.get("MUJOCO_GL"), study.__file__], display=False)
```

Preset: {glue:text}`preset`.
"""

BETA = HEADER + """
# Beta

```{code-cell} ipython3
:tags: [parameters]

preset = "paper"
```

```{code-cell} ipython3
print("beta ran with", preset)
```
"""

# plots under whatever backend the caller's MPLBACKEND asks for, and reports progress as the package does.
PLOTS = HEADER + """
# Plots

```{code-cell} ipython3
:tags: [parameters]

preset = "paper"
```

```{code-cell} ipython3
import matplotlib.pyplot as plt
from myst_nb import glue

from study.core.progress import Progress

with Progress("counting", total=3) as bar:
    for _ in range(3):
        bar.update()
fig, ax = plt.subplots()
ax.plot([0, 1], [1, 0])
plt.show()
fig2, ax2 = plt.subplots()
ax2.plot([0, 1], [0, 1])
glue("fig_glued", fig2, display=False)
plt.close(fig2)
```

```{glue:figure} fig_glued
A glued figure.
```
"""

AS_TEXT = HEADER + """
# A figure as text

```{code-cell} ipython3
from IPython.display import display

display({"text/plain": "<Figure size 640x480 with 1 Axes>"}, raw=True)
```
"""

BAD = HEADER + """
# Bad

```{code-cell} ipython3
:tags: [parameters]

preset = "paper"
```

```{code-cell} ipython3
x = 1
```

Some prose between the cells.

```{code-cell} ipython3
---
tags: [hide-input]
---
y = x / 0
```
"""


def write_book(root: Path, chapters: dict[str, str], toc: str) -> Path:
    (root / "book").mkdir(parents=True, exist_ok=True)
    (root / "_config.yml").write_text(CONFIG)
    (root / "_toc.yml").write_text(toc)
    for stem, text in chapters.items():
        (root / "book" / f"{stem}.md").write_text(text)
    return root


def executed(root: Path, stem: str) -> Path:
    return root / "_build" / "executed" / "book" / f"{stem}.ipynb"


def glued(root: Path, stem: str, name: str) -> str:
    """The text/plain of what chapter ``stem``'s executed copy glued under ``name``."""
    nb = nbformat.read(executed(root, stem), as_version=4)
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            if out.get("metadata", {}).get("scrapbook", {}).get("name") == name:
                # display=False stores it under application/papermill.record/text/plain
                return next(v for k, v in out["data"].items() if k.endswith("text/plain"))
    raise AssertionError(f"{stem} glued no {name!r}")


def ran(timings: dict) -> set[str]:
    return {stem for stem, t in timings.items() if not t["cached"]}


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A two-chapter book (and a plain page), executed once with preset 'smoke'."""
    root = write_book(tmp_path_factory.mktemp("tiny"), {"alpha": ALPHA, "beta": BETA, "notes": NOTES}, TOC)
    (root / "inputs.txt").write_text("first\n")
    book.build(root, "smoke", force=False, only=None, html=False)
    return root


# runs after every other chapter (its front matter says so) and checks that beta's key is already on disk.
LAST = HEADER.rstrip("\n").removesuffix("---") + "study:\n  execute: last\n---\n" + """
# Last

```{code-cell} ipython3
from pathlib import Path

assert Path("_build/executed/book/beta.key.json").is_file(), "beta's key is not written yet"
```
"""


@pytest.mark.slow
def test_a_chapters_key_is_written_as_it_ends_so_a_build_killed_later_keeps_it(tmp_path: Path) -> None:
    """A build killed at a session's end never reaches its last step; the chapters it executed are not lost."""
    toc = TOC.replace("  - file: book/notes\n", "  - file: book/last\n")
    root = write_book(tmp_path, {"alpha": ALPHA, "beta": BETA, "last": LAST}, toc)
    (root / "inputs.txt").write_text("first\n")
    book.build(root, "smoke", force=False, only=None, html=False)  # 'last' runs after beta and finds its key


@pytest.mark.slow
def test_a_build_stopped_before_the_recommended_model_leaves_its_chapters_unkeyed(tmp_path: Path) -> None:
    """The chapters the recommended model is made from (here a stand-in named 'usercamera') get their key only once
    the model is made: a build that stops before (here a chapter that fails last) must make it next time."""
    failing = BAD.replace("---\n\n", "study:\n  execute: last\n---\n\n", 1)
    toc = "format: jb-book\nroot: book/beta\nchapters:\n  - file: book/usercamera\n  - file: book/bad\n"
    root = write_book(tmp_path, {"beta": BETA, "usercamera": BETA, "bad": failing}, toc)
    with pytest.raises(ChapterError):
        book.build(root, "smoke", force=False, only=None, html=False)
    keys = root / "_build" / "executed" / "book"
    assert (keys / "beta.key.json").is_file() and executed(root, "usercamera").is_file()
    assert not (keys / "usercamera.key.json").exists(), "cached next time, the recommended model would never be made"


@pytest.mark.slow
def test_chapters_run_in_the_root_and_the_build_never_moves_the_process(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """Chapters execute two at a time in threads: a chdir around one would move every thread's working folder."""
    root = write_book(tmp_path / "b", {"alpha": ALPHA, "beta": BETA, "notes": NOTES}, TOC)
    (root / "inputs.txt").write_text("first\n")

    here, chdir = os.getcwd(), os.chdir

    def stay(path: str) -> None:  # papermill's file reads "chdir" to the folder they are in: allowed
        if os.path.realpath(path) != os.path.realpath(here):
            raise AssertionError(f"the build moved the process to {path}")
        chdir(path)

    monkeypatch.setattr(os, "chdir", stay)
    book.build(root, "smoke", force=False, only=None, html=False)
    assert glued(root, "alpha", "content") == "'first'", "alpha read inputs.txt from the root: its kernel ran there"


@pytest.mark.slow
def test_build_executes_injects_and_renders(tiny: Path) -> None:
    book.render_html(tiny)
    nb = nbformat.read(executed(tiny, "alpha"), as_version=4)
    injected = [c for c in nb.cells if "injected-parameters" in c.metadata.get("tags", [])]
    assert len(injected) == 1 and "preset = \"smoke\"" in injected[0].source
    assert glued(tiny, "alpha", "preset") == "'smoke'"
    hashseed, mujoco_gl, study_file = ast.literal_eval(glued(tiny, "alpha", "env"))
    assert hashseed == "0" and mujoco_gl == os.environ.get("MUJOCO_GL", "egl")
    assert Path(study_file).resolve() == Path(book.__file__).resolve().parent.parent / "__init__.py"
    html = (tiny / "_build" / "html" / "book" / "alpha.html").read_text()
    assert "Preset:" in html and "smoke" in html
    assert (tiny / "_build" / "html" / "index.html").is_file()
    timings = json.loads((tiny / "_build" / "executed" / "timings.json").read_text())
    assert timings["preset"] == "smoke"
    assert set(timings["chapters"]) == {"alpha", "beta", "notes"}
    assert timings["chapters"]["notes"]["page"]
    assert all(not t["cached"] and t["seconds"] > 0 for s, t in timings["chapters"].items() if s != "notes")
    assert "A plain page" in (tiny / "_build" / "html" / "book" / "notes.html").read_text()


def test_injected_cell_hidden_and_values_shown_in_the_parameters_cell(tiny: Path) -> None:
    nb = nbformat.read(executed(tiny, "alpha"), as_version=4)
    injected = next(c for c in nb.cells if "injected-parameters" in c.metadata.tags)
    own = next(c for c in nb.cells if "parameters" in c.metadata.get("tags", []))
    assert "remove-cell" in injected.metadata.tags
    assert 'preset = "smoke"  # set by `study book`; default "paper"' in own.source
    assert 'inputs = "inputs.txt"' in own.source  # not injected: as written


def test_second_run_executes_nothing(tiny: Path) -> None:
    before = executed(tiny, "beta").stat().st_mtime_ns
    assert ran(book.execute(tiny, "smoke")) == set()
    assert executed(tiny, "beta").stat().st_mtime_ns == before


def test_changed_chapter_reexecutes_only_it(tiny: Path) -> None:
    beta = tiny / "book" / "beta.md"
    beta.write_text(beta.read_text() + "\nOne more line of prose.\n")
    assert ran(book.execute(tiny, "smoke")) == {"beta"}
    assert ran(book.execute(tiny, "smoke")) == set()


def test_changed_input_file_reexecutes_the_chapter_that_names_it(tiny: Path) -> None:
    (tiny / "inputs.txt").write_text("second\n")
    assert ran(book.execute(tiny, "smoke")) == {"alpha"}
    assert glued(tiny, "alpha", "content") == "'second'"


def test_the_scheduler_reaches_the_chapters_that_take_it_and_stays_out_of_their_keys(tiny: Path) -> None:
    beta = tiny / "book" / "beta.md"
    beta.write_text(beta.read_text().replace('preset = "paper"\n```', 'preset = "paper"\nscheduler = ""\n```', 1)
                    + "\n```{code-cell} ipython3\nfrom myst_nb import glue\n\nglue('scheduler', scheduler)\n```\n")
    address = "tcp://192.0.2.1:8786"  # never contacted: the chapter only shows it
    assert ran(book.execute(tiny, "smoke", scheduler=address)) == {"beta"}, "alpha declares no scheduler"
    assert glued(tiny, "beta", "scheduler") == repr(address)
    assert ran(book.execute(tiny, "smoke")) == set(), "where the runs go is not part of what they compute"


@pytest.mark.slow  # starts a Dask LocalCluster
def test_scheduler_local_starts_one_cluster_on_the_loopback_only() -> None:
    from study.book import builder

    with builder._cluster("local") as address:
        assert address.startswith("tcp://127.0.0.1:")
    with builder._cluster("tls://scheduler.example:8786") as address:
        assert address == "tls://scheduler.example:8786", "an address is handed on as it is"


def test_other_preset_reexecutes_everything(tiny: Path) -> None:
    # Keys include the injected parameters: no copy made with one preset is reused for another.
    assert ran(book.execute(tiny, "paper")) == {"alpha", "beta"}
    assert ran(book.execute(tiny, "paper")) == set()


def test_only_executes_the_named_chapter_and_says_so_on_a_chapter_never_executed(tiny: Path) -> None:
    executed(tiny, "alpha").unlink()
    timings = book.execute(tiny, "paper", only=["beta"])
    assert ran(timings) == {"beta"} and timings["alpha"].get("absent")
    page = nbformat.read(executed(tiny, "alpha"), as_version=4)
    assert [c.cell_type for c in page.cells] == ["markdown"] and "Not executed in this build" in page.cells[0].source
    assert page.cells[0].source.startswith("# "), "the page keeps its title for the table of contents"
    table = book.timings_table(timings)
    assert "alpha  not executed" in table and "cached" not in table, "the build's last table does not call it cached"
    assert ran(book.execute(tiny, "paper")) == {"alpha"}, "the next full build executes it"


def test_only_unknown_chapter_is_a_config_error(tiny: Path) -> None:
    with pytest.raises(ConfigError, match=r"gamma.*alpha, beta, notes"):
        book.execute(tiny, "smoke", only=["gamma"])


def test_unknown_preset_is_a_config_error(tiny: Path) -> None:
    with pytest.raises(ConfigError, match="preset"):
        book.build(tiny, "huge", force=False, only=None, html=False)


def test_toc_naming_a_missing_chapter_is_a_config_error(tmp_path: Path) -> None:
    write_book(tmp_path, {"alpha": ALPHA, "notes": NOTES}, TOC)
    with pytest.raises(ConfigError, match=r"book/beta"):
        book.chapters(tmp_path)


def test_missing_toc_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="_toc.yml"):
        book.chapters(tmp_path)


def test_folder_fingerprint_follows_the_files_inside(tmp_path: Path) -> None:
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "a.bin").write_bytes(b"1")
    params = {"data_dir": "d", "preset": "smoke", "nothing": "no-such-file", "n": 3, "up": "..", "here": "."}
    first = book.inputs_fingerprint(tmp_path, params)
    assert set(first) == {"data_dir"}
    (tmp_path / "d" / ".b.bin.x1y2.tmp").write_bytes(b"22")  # an atomic write in progress
    assert book.inputs_fingerprint(tmp_path, params) == first
    (tmp_path / "d" / "b.bin").write_bytes(b"22")
    assert book.inputs_fingerprint(tmp_path, params) != first


@pytest.mark.slow
def test_a_sphinx_warning_fails_the_html_build(tmp_path: Path) -> None:
    write_book(tmp_path, {"notes": NOTES + "\nSee {ref}`no-such-label`.\n"}, "format: jb-book\nroot: book/notes\n")
    with pytest.raises(ChapterError, match="jupyter-book build failed"):
        book.build(tmp_path, "smoke", force=False, only=None, html=True)


@pytest.mark.slow
def test_figures_are_images_whatever_the_callers_backend_and_progress_reaches_the_terminal(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("MPLBACKEND", "Agg")  # a headless server's setting: the kernel must still show images
    write_book(tmp_path, {"plots": PLOTS}, "format: jb-book\nroot: book/plots\n")
    book.build(tmp_path, "smoke", force=False, only=None, html=True)
    nb = nbformat.read(executed(tmp_path, "plots"), as_version=4)
    images = [k for c in nb.cells for o in c.get("outputs", []) for k in o.get("data", {}) if k.endswith("image/png")]
    assert len(images) == 2  # the plt.show() figure and the glued one
    html = (tmp_path / "_build" / "html" / "book" / "plots.html").read_text()
    assert html.count("<img") >= 2 and "Figure size" not in html
    err = capsys.readouterr().err
    assert "plots · counting" in err  # the kernel's progress, on the builder's terminal
    assert "chapters:" in err and "executed in" in err and "the book: " in err


def test_a_figure_shown_as_text_fails_the_chapter(tmp_path: Path) -> None:
    write_book(tmp_path, {"astext": AS_TEXT}, "format: jb-book\nroot: book/astext\n")
    with pytest.raises(ChapterError, match=r"astext.md: cell \d+ showed a figure as text"):
        book.build(tmp_path, "smoke", force=False, only=None, html=False)
    assert not executed(tmp_path, "astext").exists()


@pytest.fixture
def bad_book(tmp_path: Path) -> Path:
    return write_book(tmp_path, {"bad": BAD}, "format: jb-book\nroot: book/bad\n")


def test_failing_cell_names_chapter_and_cell_and_keeps_no_complete_copy(bad_book: Path) -> None:
    stale = executed(bad_book, "bad")
    stale.parent.mkdir(parents=True)
    stale.write_text("{}")  # a copy from an earlier, successful run
    with pytest.raises(ChapterError) as info:
        book.build(bad_book, "smoke", force=False, only=None, html=False)
    msg = str(info.value)
    assert "book/bad.md" in msg
    assert "cell 4" in msg and "y = x / 0" in msg and "book/bad.md:31" in msg
    assert "ZeroDivisionError" in msg
    assert "_build/failed/book/bad.ipynb" in msg
    assert not stale.exists()
    assert (bad_book / "_build" / "failed" / "book" / "bad.ipynb").is_file()
    assert not list((bad_book / "_build" / "executed" / "book").glob("*.ipynb"))
    timings = json.loads((bad_book / "_build" / "executed" / "timings.json").read_text())
    assert timings["chapters"]["bad"]["failed"]


def test_cli_on_a_failing_book_prints_one_line_and_exits_2(
    bad_book: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["book", "--root", str(bad_book), "--preset", "smoke", "--no-build"]) == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("study: error:")]
    assert len(errors) == 1 and "book/bad.md" in errors[0] and "ZeroDivisionError" in errors[0]


def test_cli_only_unknown_chapter_exits_2(tiny: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["book", "--root", str(tiny), "--only", "gamma", "--no-build"]) == 2
    assert "no such chapter" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.book
def test_repo_book_builds_with_smoke_preset(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                           capfd: pytest.CaptureFixture[str]) -> None:
    """The real book, preset 'smoke', in a scratch root that links to the repo's sources.

    Nothing is written into the project: the scratch root has its own data/ and _build/. MPLBACKEND=Agg,
    as on many servers, must not turn the figures into text.
    """
    for entry in REPO.iterdir():
        if entry.name not in {"_build", ".git", ".venv", ".pytest_cache", "data"}:
            os.symlink(entry, tmp_path / entry.name)
    (tmp_path / "data").mkdir()
    monkeypatch.setenv("MPLBACKEND", "Agg")
    book.build(tmp_path, "smoke", force=False, only=None, html=True)
    log = capfd.readouterr().err
    assert "KeyboardInterrupt caught" not in log, "a chapter stopped for its runs is not an error in the build's log"
    timings = json.loads((tmp_path / "_build" / "executed" / "timings.json").read_text())
    assert len(timings["stages"]) >= 2, "a cold build plans its runs in stages: the grid, then what its winner needs"
    assert all(s["runs"] > 0 and s["chapters"] for s in timings["stages"])
    renders = timings["render_cpu_seconds"]  # the sweep's and the floor path's clips, rendered by this build
    assert set(renders) == {"sweep", "floor development clips"} and all(v > 0 for v in renders.values()), renders
    records = sorted((tmp_path / "data" / "runs").glob("*.json"))
    again = book.execute(tmp_path, "smoke", only=["table1", "decision"])  # every run they ask for is trained
    assert not json.loads((tmp_path / "_build" / "executed" / "timings.json").read_text())["stages"]
    assert sorted((tmp_path / "data" / "runs").glob("*.json")) == records, "executing after the plan trains no run"
    from study.runs import measured, recommended

    rec = recommended.read(tmp_path / "data")  # the model `study classify` uses without --model
    assert rec.preset == "smoke" and rec.key and all(m.is_dir() for m in rec.path().models)
    chosen = measured.candidate_kind(rec.path().name)
    assert set(rec.path().accuracy) >= {"exact", "mean"} and rec.path().accuracy == rec.measured[chosen]
    assert set(rec.paths) == set(recommended.PATHS), "a model for one scale and one for the floor path"
    floor = rec.path(recommended.FLOOR)
    assert floor.accuracy == rec.measured[measured.candidate_kind(floor.name)] and "floor" in floor.accuracy
    assert rec.path().band == (0.0, 1.0), "8 throws a class certify no side: every answer is 'cannot tell'"
    assert not again["table1"]["cached"] and "waited" not in again["table1"]
    index = tmp_path / "_build" / "html" / "book" / "intro.html"
    assert "The motion-pattern study" in index.read_text()
    figures = 0
    for ch in book.chapters(tmp_path):
        page = tmp_path / "_build" / "html" / "book" / f"{ch.stem}.html"
        text = page.read_text()  # Sphinx's smart quotes turn a table's |---| into |—| when it is left as text
        assert "|---|" not in text and "|\u2014|" not in text, f"{ch.stem}: a Markdown table was rendered as text"
        assert "Figure size" not in text, f"{ch.stem}: a figure was rendered as text"
        assert "injected by papermill" not in text.lower() and "# Parameters" not in text, ch.stem
        if ch.source.read_text().startswith("---\njupytext"):
            assert "preset build, for tests" in text, f"{ch.stem}: a smoke page must say so at its top"
            nb = nbformat.read(ch.executed, as_version=4)
            pngs = sum(k.endswith("image/png") for c in nb.cells for o in c.get("outputs", []) for k in o.get("data", {}))
            assert text.count("<img") >= pngs, ch.stem
            figures += pngs
    assert figures >= 9  # the smoke book has nine figures at least, each an image
    api = (tmp_path / "_build" / "html" / "book" / "api.html").read_text()
    assert all(f'id="study.{name}"' in api for name in ("fit", "dataset", "classify", "TrainConfig")), "autodoc ran"
    tutorial = (tmp_path / "_build" / "html" / "book" / "tutorial.html").read_text()
    assert "test accuracy" in tutorial and "trust: " in tutorial and "executed:" in tutorial, "every step ran"
    from study.book import results, summary

    built = results.load(tmp_path / results.FILE)  # refuses a stored verdict its inputs do not decide
    readme = tmp_path / "README-copy.md"  # the README's findings, written from this build's results
    readme.write_text("before\n<!-- findings: begin -->\nSTALE-BLOCK\n<!-- findings: end -->\nafter\n")
    script = [sys.executable, str(REPO / "scripts" / "readme_findings.py"), str(tmp_path / results.FILE)]
    assert subprocess.run([*script, "--commit", "abc1234", "--write", str(readme)], timeout=120).returncode == 0
    text = readme.read_text()
    assert text.startswith("before\n<!-- findings: begin -->") and text.endswith("<!-- findings: end -->\nafter\n")
    assert "`abc1234`" in text and "| Table 1, Z only | 78 % |" in text and "STALE-BLOCK" not in text
    recipe = "usercamera.sweep.kind.positions-any-camera.mean" in built  # the README recipe's kind, where scored
    assert ("a model like the recipe's below" in text) == recipe, "the recipe's model on video, when measured"
    late = built["table1.z.unsettled_picks"].value + built["table1.xyz.unsettled_picks"].value
    assert ("runs validation picks not settled" in text) == (late > 0), "Table 1's rows say when a pick had not settled"
    decided = [n for n in built.values() if n.verdict]
    assert len(decided) >= 15 and results.recompute(built) == [], "every verdict follows from its stored inputs"
    page = summary.compute(tmp_path / results.FILE, "smoke")  # the summary page's rows, read as typed results
    assert page.chapters.unread(built) == [], "every learner, protocol, family and path written is read back"
    added = {**built, "usercamera.sweep.fisheye.clips": built["usercamera.sweep.low.clips"]}  # a family not defined
    assert page.chapters.unread(added) == ["usercamera.sweep.fisheye.clips"], "so a family added by hand is caught"
    assert len(page.rows) == len(summary.ROWS) and all(r.verdict for r in page.rows)
    assert all(r.ours for r in page.rows if r.kind in ("number", "order")), "every row of the summary has its number"
    assert f"Of its {len(page.rows)} tables, figures and claims" in page.findings, "the findings count every row"
    assert len(page.forest.numbers) == 4, "Table 1's two rows in both engines, each against the paper's number"
    assert [p.ceiling for p in page.allows.panels] == [page.chapters.motion.ceiling.air_on,
                                                        page.chapters.motion.ceiling.air_off]


def test_chapters_show_the_code_that_teaches_not_the_plumbing() -> None:
    """Cells a reader sees hold no glue(...) calls (those only hand numbers to the prose: hidden cells), and
    no code line a reader can open (visible or folded) runs past the page's edge (90 characters)."""
    import jupytext

    hidden = {"remove-cell", "remove-input"}
    for source in sorted((REPO / "book").glob("*.md")):
        nb = jupytext.read(source, fmt="md:myst")
        for i, cell in enumerate(c for c in nb.cells if c.cell_type == "code"):
            tags = set(cell.metadata.get("tags", []))
            if tags & hidden:
                continue
            lines = cell.source.splitlines()
            assert all(len(line) <= 90 for line in lines), f"{source.name}, code cell {i}: a line over 90 characters"
            if "hide-input" not in tags:
                assert not any("glue(" in line for line in lines), f"{source.name}, code cell {i}: glue in a shown cell"


def test_no_line_of_prose_starts_with_a_percent_sign() -> None:
    """MyST reads a line that starts with ``%`` as a comment and drops it: a rewrapped sentence ("gets 71.0
    % of the test throws right") would lose its second half without a warning."""
    import jupytext

    for source in sorted((REPO / "book").glob("*.md")):
        nb = jupytext.read(source, fmt="md:myst")
        for cell in nb.cells:
            if cell.cell_type == "markdown":
                bad = [line for line in cell.source.splitlines() if line.lstrip().startswith("%")]
                assert not bad, f"{source.name}: a line MyST would drop as a comment: {bad[0][:60]!r}"


def test_no_chapter_hides_more_than_15_lines_of_code() -> None:
    """A chapter's science lives in the package: its hidden cells (remove-cell, remove-input, hide-input,
    hide-cell) hold at most 15 code lines that are not blank and not comments, parameter and import cells
    included (as ../shared/tools/hidden_lines.py counts them)."""
    import jupytext

    hidden_tags = {"remove-cell", "remove-input", "hide-input", "hide-cell"}
    for source in sorted((REPO / "book").glob("*.md")):
        nb = jupytext.read(source, fmt="md:myst")
        hidden = sum(1 for c in nb.cells if c.cell_type == "code" and hidden_tags & set(c.metadata.get("tags", []))
                     for line in c.source.splitlines() if line.strip() and not line.strip().startswith("#"))
        assert hidden <= 15, f"{source.name}: {hidden} hidden code lines; move the computation into study"


def test_no_chapter_types_a_verdict() -> None:
    """Verdicts are decided by study.report.verdicts from numbers, never written: no code cell of any chapter
    passes a verdict word as a string literal to anything that records or builds a verdict, or compares a verdict
    with one to choose another."""
    import jupytext

    from study.report import verdicts

    words = set(verdicts.VERDICTS)
    takers = {"verdict", "add", "Decision", "combine", "Verdict", "number", "order", "combined"}
    for source in sorted((REPO / "book").glob("*.md")):
        nb = jupytext.read(source, fmt="md:myst")
        for i, cell in enumerate(c for c in nb.cells if c.cell_type == "code"):
            code = "\n".join(ln for ln in cell.source.splitlines() if not ln.lstrip().startswith(("%", "!")))
            for node in ast.walk(ast.parse(code)):
                if not isinstance(node, ast.Call):
                    continue
                name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
                if name not in takers:
                    continue
                args = list(node.args) + [k.value for k in node.keywords]
                for a in args:
                    for leaf in ast.walk(a):
                        assert not (isinstance(leaf, ast.Constant) and leaf.value in words), \
                            f"{source.name}, code cell {i}: the verdict {leaf.value!r} is typed in a call to {name}()"


def test_a_library_banner_is_dropped_from_the_printed_output_and_nothing_else() -> None:
    import nbformat

    from study.book import nbtidy

    nb = nbformat.v4.new_notebook()
    banner = nbformat.v4.new_output("stream", name="stdout", text="pybullet build time: Jan 29 2025 23:17:20\n")
    mixed = nbformat.v4.new_output("stream", name="stdout", text="a\npybullet build time: Jan 1 2020\nb\n")
    figure = nbformat.v4.new_output("display_data", data={"text/plain": "x"})
    nb.cells = [nbformat.v4.new_code_cell("import study", outputs=[banner, mixed, figure])]
    outputs = nbtidy.drop_banners(nb).cells[0].outputs
    assert [o.output_type for o in outputs] == ["stream", "display_data"], "the banner-only output removed"
    assert outputs[0]["text"] == "a\nb\n"


NAMED_PENDING = HEADER + """
# An exception that only shares the name

```{code-cell} ipython3
:tags: [parameters]

preset = "paper"
```

```{code-cell} ipython3
import os

from study.core import ticket

seen = ticket.current()
assert os.path.exists(os.environ[ticket.ENV]) and seen.results and seen.plan and seen.progress and seen.pending
assert not [k for k in os.environ if k.startswith("STUDY_") and k != ticket.ENV], "one variable: the ticket"


class Pending(Exception):
    pass


raise Pending("listed nothing")
```
"""


def test_a_chapter_stops_for_runs_only_when_its_ticket_lists_them(tmp_path: Path) -> None:
    """The builder tells a chapter everything through its ticket (one environment variable), and reads from the
    ticket whether a chapter that stopped asked for runs: an exception that merely shares the name ``Pending``, with
    no runs listed, is a failure of the chapter, not a wait."""
    root = write_book(tmp_path, {"named": NAMED_PENDING}, "format: jb-book\nroot: book/named\n")
    with pytest.raises(ChapterError, match="Pending: listed nothing"):
        book.build(root, "smoke", force=False, only=None, html=False)


def test_the_build_loop_waits_only_on_what_is_not_done():
    """A done future in the wait set ends every wait at once: the builder's loop would spin a core at 100 % while a
    stopped chapter waits for its other runs (the first cold paper build of the EMA recipe did, for hours)."""
    from concurrent.futures import Future

    from study.book.builder import _to_await

    done, busy, chapter = Future(), Future(), Future()
    done.set_result([])
    waiting = {"table1": (None, [done, busy], (2, 2), 0.0)}
    assert _to_await({chapter: None}, waiting) == {chapter, busy}
    busy.set_result([])
    assert _to_await({}, waiting) == set()


def test_a_page_built_with_a_small_preset_says_so_under_its_title_and_the_studys_does_not() -> None:
    import nbformat

    from study.book import nbtidy

    def page():
        nb = nbformat.v4.new_notebook()
        nb.cells = [nbformat.v4.new_markdown_cell("# Table 1\n\nThe answer."), nbformat.v4.new_code_cell("1")]
        return nb

    smoke = nbtidy.preset_warning(page(), "smoke").cells[0].source
    assert smoke.startswith("# Table 1\n\n```{warning}") and "**smoke** preset build, for tests" in smoke and smoke.endswith("The answer.")
    assert nbtidy.preset_warning(page(), "paper").cells[0].source == "# Table 1\n\nThe answer."
