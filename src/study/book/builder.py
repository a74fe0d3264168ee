"""Build the book: execute each chapter with papermill (cached by content), then render with Jupyter Book.

A chapter is a jupytext MyST markdown file ``book/<stem>.md`` listed in ``_toc.yml``. It is executed
with the preset injected into its ``parameters`` cell, into ``_build/executed/book/<stem>.ipynb``;
``jupyter-book build`` then renders those executed copies with execution off, failing on warnings.

An executed copy is reused while its key is unchanged: the key hashes the chapter's source, the
injected parameters, the ``study`` package's source, and every file or folder that a string parameter
of the chapter names (so a new dataset re-executes the chapters that read it). Copies are written
atomically; a chapter that fails leaves its partial copy in ``_build/failed/`` for inspection, never
where a complete one is read. A markdown page without a kernel (e.g. the references) is copied as is.
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from tqdm import tqdm

import study
from study.book import nbtidy, results
from study.core import datadir, presets, ticket
from study.core.cache import canonical_json, key, source_hash, write_text_atomic
from study.core.errors import ChapterError, ConfigError, check_writable
from study.core.progress import Follower
from study.runs import cluster, failures

RUNTIME = ("scheduler",)
"""Parameters that say where a chapter's work runs, not what it computes: injected into the chapters that
declare them, and left out of every chapter's cache key."""

EXECUTED = Path("_build/executed")
"""Where executed copies (and the staged book sources) go, relative to the root."""
FAILED = Path("_build/failed")
"""Where the partial copy of a chapter that failed is kept for inspection."""
RUNNING = Path("_build/running")
"""Where papermill writes while a chapter runs (never read as complete)."""
STAGED = ("_config.yml", "_toc.yml")
"""Root files the Jupyter Book build needs beside the executed chapters."""
STAGED_IF_PRESENT = ("references.bib",)
KERNEL = "python3"


@dataclass(frozen=True)
class Chapter:
    """One entry of the table of contents."""

    entry: str  # as written in _toc.yml, e.g. "book/data"
    root: Path

    @property
    def stem(self) -> str:
        return Path(self.entry).name

    @property
    def source(self) -> Path:
        return self.root / f"{self.entry}.md"

    @property
    def executed(self) -> Path:
        return self.root / EXECUTED / f"{self.entry}.ipynb"

    @property
    def key_file(self) -> Path:
        return self.root / EXECUTED / f"{self.entry}.key.json"

    @property
    def results_part(self) -> Path:
        """The numbers this chapter reported in its last run (``study.book.results``)."""
        return self.root / EXECUTED / "results" / f"{self.entry}.json"

    @property
    def plan_part(self) -> Path:
        """The training runs this chapter asked for in its last run (``study.runs.schedule.Plan``)."""
        return self.root / EXECUTED / "plans" / f"{self.entry}.jsonl"

    @property
    def failed(self) -> Path:
        return self.root / FAILED / f"{self.entry}.ipynb"


# ---------------------------------------------------------------------------------------------
# The table of contents


def _toc_files(node: Any) -> Iterator[str]:
    """Every ``file:`` of a sphinx-external-toc tree, in reading order."""
    if isinstance(node, dict):
        if "file" in node:
            yield str(node["file"])
        for k in ("parts", "chapters", "sections"):
            for child in node.get(k) or []:
                yield from _toc_files(child)
    elif isinstance(node, list):
        for child in node:
            yield from _toc_files(child)


def chapters(root: Path) -> list[Chapter]:
    """The chapters listed in ``<root>/_toc.yml`` (its ``root`` first), in order.

    Raises :class:`ConfigError` if the toc is missing or malformed, names a file that does not exist,
    or two chapters share a stem.
    """
    toc_path = root / "_toc.yml"
    if not toc_path.is_file():
        raise ConfigError(f"{toc_path}: no table of contents; run 'study book' from the project root or pass --root")
    try:
        toc = yaml.safe_load(toc_path.read_text())
    except yaml.YAMLError as e:
        raise ConfigError(f"{toc_path}: not valid YAML ({e}); fix the file") from e
    if not isinstance(toc, dict) or "root" not in toc:
        raise ConfigError(f"{toc_path}: needs 'format: jb-book' and a 'root:' entry (e.g. 'root: book/intro')")
    entries = [str(toc["root"]), *_toc_files({k: v for k, v in toc.items() if k != "root"})]
    result, seen = [], {}
    for entry in entries:
        entry = entry.removesuffix(".md")
        ch = Chapter(entry, root)
        if not ch.source.is_file():
            raise ConfigError(f"{toc_path} lists '{entry}' but {ch.source} does not exist; add the file or remove the entry")
        if ch.stem in seen:
            raise ConfigError(f"{toc_path}: '{entry}' and '{seen[ch.stem]}' share the name '{ch.stem}'; rename one")
        seen[ch.stem] = entry
        result.append(ch)
    return result


# ---------------------------------------------------------------------------------------------
# Cache keys


def _read_notebook(path: Path) -> Any:
    """The chapter's jupytext source as an nbformat notebook."""
    import jupytext

    return jupytext.read(path, fmt="md:myst")


def _runs_last(nb: Any) -> bool:
    """A chapter whose front matter says ``study: {execute: last}`` runs after every other chapter (wherever
    the table of contents places it), once the results file holds their numbers."""
    return (nb.metadata.get("study") or {}).get("execute") == "last"


def _is_notebook(nb: Any) -> bool:
    """A page with a kernelspec in its header is executed; a plain markdown page is copied."""
    return "kernelspec" in nb.metadata


def notebook_parameters(nb_path: Path, injected: dict[str, Any]) -> dict[str, Any]:
    """The parameters a run of the notebook at ``nb_path`` (.ipynb) sees: defaults updated by ``injected``.

    Defaults that are not Python literals (expressions) are left out: they cannot name an input.
    """
    import papermill

    values: dict[str, Any] = {}
    for name, info in papermill.inspect_notebook(str(nb_path)).items():
        with contextlib.suppress(ValueError, SyntaxError, TypeError):
            values[name] = ast.literal_eval(info["default"])
    values.update(injected)
    return values


def _fingerprint_path(p: Path) -> list[Any]:
    """A file: its size and SHA-256. A folder: every file inside by relative name, size and mtime.

    Hidden files are left out: they include the temporary files of atomic writes still in progress.
    """
    if p.is_file():
        return ["file", p.stat().st_size, hashlib.sha256(p.read_bytes()).hexdigest()]
    files = []
    for f in sorted(p.rglob("*")):
        rel = f.relative_to(p)
        if f.is_file() and not any(part.startswith(".") for part in rel.parts):
            try:
                st = f.stat()
            except FileNotFoundError:  # removed since the listing (a chapter still running replaced it)
                continue
            files.append([rel.as_posix(), st.st_size, st.st_mtime_ns])
    return ["dir", files]


def inputs_fingerprint(root: Path, parameters: dict[str, Any]) -> dict[str, Any]:
    """For each string parameter that names an existing file or folder (relative to ``root``), its fingerprint."""
    out: dict[str, Any] = {}
    here = root.resolve()
    for name, value in sorted(parameters.items()):
        if not isinstance(value, str) or not value.strip():
            continue
        try:
            p = (root / value).resolve()
            if here.is_relative_to(p) or not p.exists():
                continue  # the project itself or a folder above it is not an input
        except (OSError, ValueError):
            continue
        out[name] = [value, _fingerprint_path(p)]
    return out


# ---------------------------------------------------------------------------------------------
# Execution


def _kernel_environment(ticket_file: Path | None = None) -> dict[str, str]:
    """Environment the kernel starts with (the builder's own is left alone: two chapters run at once): headless
    MuJoCo, fixed hash seed, the inline matplotlib backend, this very ``study``, and the chapter's ticket
    (``study.core.ticket``: where its progress, numbers and plan go, its device, where it lists runs not trained
    yet), the one thing the builder tells a chapter."""
    env = dict(os.environ)
    env.setdefault("MUJOCO_GL", "egl")
    env["PYTHONHASHSEED"] = "0"
    # Figures as images whatever the caller's MPLBACKEND (Agg, common on servers, would show them as text).
    env["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"
    # The kernel must import the same package whose source the cache key hashed.
    src = str(Path(study.__file__).resolve().parent.parent)
    path = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    env["PYTHONPATH"] = os.pathsep.join([src, *[p for p in path if p != src]])
    if ticket_file is not None:
        env[ticket.ENV] = str(ticket_file)
    return env


def _kernel_manager(env: dict[str, str]) -> type:
    """A kernel manager class whose kernels start with ``env`` (papermill hands nbclient the class, not the
    environment)."""
    from jupyter_client.manager import AsyncKernelManager

    class WithEnvironment(AsyncKernelManager):  # type: ignore[misc]
        async def start_kernel(self, **kw: Any) -> None:  # type: ignore[override]
            await super().start_kernel(**{"env": env, **kw})

    return WithEnvironment


_FENCE = re.compile(r"^(`{3,}|~{3,})\{code-cell\}")


def _source_line(source: Path, code_ordinal: int) -> int | None:
    """1-based line in the MyST file of the first source line of its ``code_ordinal``-th code cell."""
    lines = source.read_text().splitlines()
    fences = [i for i, line in enumerate(lines) if _FENCE.match(line)]
    if code_ordinal >= len(fences):
        return None
    i = fences[code_ordinal] + 1
    if i < len(lines) and lines[i].strip() == "---":  # YAML options block
        i += 1
        while i < len(lines) and lines[i].strip() != "---":
            i += 1
        i += 1
    while i < len(lines) and lines[i].startswith(":") and ":" in lines[i][1:]:  # short options
        i += 1
    while i < len(lines) and not lines[i].strip():
        i += 1
    return i + 1


def _failure_message(ch: Chapter, err: Any, nb: Any, root: Path) -> str:
    """One sentence naming the chapter, the cell, the exception and where the partial copy is."""
    from papermill.exceptions import PapermillExecutionError

    rel_src = ch.source.relative_to(root)
    rel_failed = ch.failed.relative_to(root)
    if not isinstance(err, PapermillExecutionError):
        return f"chapter {rel_src} failed: {type(err).__name__}: {err}; the partial copy is in {rel_failed}"
    # papermill injects a cell after the `parameters` cell (at the top if there is none); the source
    # has no such cell, so indices past it shift by one.
    tagged = [i for i, c in enumerate(nb.cells) if "parameters" in c.get("metadata", {}).get("tags", [])]
    p = tagged[0] if tagged else -1
    index = err.cell_index if err.cell_index <= p else err.cell_index - 1
    code_ordinal = sum(1 for c in nb.cells[:index] if c.cell_type == "code")
    first = next((s for s in str(err.source).splitlines() if s.strip()), "").strip()
    line = _source_line(ch.source, code_ordinal)
    where = f"{rel_src}:{line}" if line else str(rel_src)
    evalue = " ".join(str(err.evalue).split())
    return (
        f"chapter {rel_src} failed in cell {index} ({where}: `{first}`): {err.ename}: {evalue}; "
        f"the partial executed copy is in {rel_failed}"
    )


def _execute(ch: Chapter, source_nb: Path, nb: Any, parameters: dict[str, Any], root: Path, pending: Path | None = None,
             device: str = "", data_dir: Path | None = None) -> None:
    """Run ``source_nb`` (the chapter ``nb`` as .ipynb) with papermill into its executed copy, atomically, with a
    ticket that gives it its files, its ``device`` and, in a planned build, ``pending``: where it lists the runs it
    needs that are not trained yet.

    Raises :class:`_Pending` if the chapter stopped after listing runs there (its ticket says so), and
    :class:`ChapterError` if a cell fails or the kernel dies; the partial copy goes to ``_build/failed/`` and any
    older executed copy of the chapter is removed.
    """
    import nbformat
    import papermill
    from nbclient.exceptions import DeadKernelError
    from papermill.exceptions import PapermillExecutionError

    running = root / RUNNING / f"{ch.entry}.ipynb"
    running.parent.mkdir(parents=True, exist_ok=True)
    follow = running.with_suffix(".progress")
    if pending is not None:
        pending.unlink(missing_ok=True)  # what this execution asks for, nothing older
    chapter_ticket = ticket.Ticket(chapter=ch.stem, progress=str(follow), results=str(ch.results_part),
                                   plan=str(ch.plan_part), pending=str(pending or ""), device=device,
                                   data_dir=str(data_dir or ""))
    ticket_file = chapter_ticket.write(running.with_suffix(".ticket.json"))
    ch.results_part.unlink(missing_ok=True)  # written afresh by this run, or not at all
    ch.plan_part.unlink(missing_ok=True)
    ch.plan_part.parent.mkdir(parents=True, exist_ok=True)
    try:
        with Follower(follow, ch.stem):
            papermill.execute_notebook(
                str(source_nb),
                str(running),
                parameters=parameters,
                kernel_name=KERNEL,
                # The kernel starts in the root (nbclient's resources path), and the process stays where it is:
                # papermill's cwd= would chdir the whole process around each chapter, and chapters run two at a
                # time in threads, so two of them restoring out of order left the caller in the book's root.
                resources={"metadata": {"path": str(root)}},
                progress_bar=False,  # the Follower shows what the chapter is doing instead
                log_output=False,
                # The kernel's own log (not the cells' output) warns that its local TCP link is unencrypted and,
                # when a chapter that stopped for its runs is shut down, logs the interrupt as an error; a cell's
                # error and a dead kernel reach the build as exceptions, not through this log.
                extra_arguments=["--IPKernelApp.log_level=CRITICAL"],
                # A cell's output may reach the client seconds after its reply on a loaded machine (two chapters,
                # a render and training on two cores); nbclient's 4 s wait for it then failed the chapter.
                iopub_timeout=120,
                kernel_manager_class=_kernel_manager(_kernel_environment(ticket_file)),
            )
    except PapermillExecutionError as e:
        if chapter_ticket.asked():  # it listed runs not trained yet: the build trains them, then runs it again
            running.unlink(missing_ok=True)
            raise _Pending(ch.stem) from None
        _keep_failed(ch, running)
        raise ChapterError(_failure_message(ch, e, nb, root)) from None
    except DeadKernelError as e:
        _keep_failed(ch, running)
        raise ChapterError(_failure_message(ch, e, nb, root)) from None
    except BaseException:
        running.unlink(missing_ok=True)
        raise
    finally:
        follow.unlink(missing_ok=True)
        ticket_file.unlink(missing_ok=True)
    executed = nbformat.read(running, as_version=4)
    as_text = nbtidy.figures_as_text(executed)
    if as_text:
        _keep_failed(ch, running)
        raise ChapterError(
            f"chapter {ch.source.relative_to(root)}: cell {as_text[0]} showed a figure as text "
            f"('<Figure size ...>'), not as an image: the kernel's matplotlib backend is not the inline one; "
            f"the partial copy is in {ch.failed.relative_to(root)}"
        )
    tidy = nbtidy.drop_banners(nbtidy.show_parameters_once(executed, parameters))
    nbformat.write(nbtidy.preset_warning(tidy, str(parameters.get("preset", nbtidy.STUDY_PRESET))), running)
    ch.executed.parent.mkdir(parents=True, exist_ok=True)
    os.replace(running, ch.executed)  # same filesystem: the complete copy appears in one step
    ch.failed.unlink(missing_ok=True)


class _Pending(Exception):
    """A chapter stopped at runs not trained yet, which it listed in its ticket's ``pending`` file."""


def _keep_failed(ch: Chapter, running: Path) -> None:
    """Move a failed chapter's partial copy to ``_build/failed/`` and forget its old executed copy."""
    ch.executed.unlink(missing_ok=True)
    ch.key_file.unlink(missing_ok=True)
    ch.results_part.unlink(missing_ok=True)
    ch.plan_part.unlink(missing_ok=True)
    ch.failed.parent.mkdir(parents=True, exist_ok=True)
    if running.exists():
        os.replace(running, ch.failed)


def _write_key(ch: Chapter, base: dict[str, Any], parameters: dict[str, Any], root: Path, seconds: float) -> None:
    """Record the key the executed copy answers to (inputs fingerprinted as they are now)."""
    k = key({**base, "inputs": inputs_fingerprint(root, parameters)}, length=64)
    write_text_atomic(ch.key_file, json.dumps({"key": k, "seconds": round(seconds, 3)}, indent=1) + "\n")


def _stored(ch: Chapter) -> dict[str, Any] | None:
    if not ch.executed.is_file() or not ch.key_file.is_file():
        return None
    try:
        return json.loads(ch.key_file.read_text())
    except (json.JSONDecodeError, OSError):
        return None


# ---------------------------------------------------------------------------------------------
# The whole build


def _decide(ch: Chapter, current: str, force: bool, only: list[str] | None,
            reads_all: bool = False) -> tuple[str, dict[str, Any]]:
    """``("cached" | "kept" | "absent" | "execute", stored key record)`` for one chapter. With ``only``, a
    chapter not named is kept as it is (out of date or, never executed, ``"absent"``), unless a chapter named
    reads every chapter's results (``reads_all``): then one never executed is executed."""
    stored = _stored(ch) or {}
    if force or (only is not None and ch.stem in only):
        return "execute", stored
    if stored.get("key") == current:
        return "cached", stored
    if only is not None and ch.executed.is_file():
        return "kept", stored  # out of date, but the user asked for other chapters only
    if only is not None and not reads_all:
        return "absent", stored
    return "execute", stored


def _placeholder(ch: Chapter, only: list[str]) -> None:
    """An executed copy of ``ch`` that says it was not executed (``--only`` named other chapters), so the book
    still builds; it has no key, so the next build without ``--only`` executes the chapter."""
    import nbformat

    title = next((line for line in ch.source.read_text().splitlines() if line.startswith("# ")), f"# {ch.stem}")
    text = (f"{title}\n\n*Not executed in this build*: `study book --only {' '.join(only)}` asked for other "
            f"chapters. Run `study book --only {ch.stem}`, or `study book`, to execute it.")
    ch.key_file.unlink(missing_ok=True)  # an older execution's key must not vouch for this page
    ch.executed.parent.mkdir(parents=True, exist_ok=True)
    page = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell(text)])
    write_text_atomic(ch.executed, nbformat.writes(page))


def execute(root: Path, preset: str, force: bool = False, only: list[str] | None = None,
            scheduler: str = "", device: str = "cpu", workers: int = 0,
            data_dir: Path | None = None) -> dict[str, dict[str, Any]]:
    """Execute (or reuse) every chapter of ``root``'s book; returns {stem: {"seconds", "cached", ...}}.

    ``force`` re-executes every chapter; ``only`` (stems) re-executes just those, keeping the others' current
    copies; a chapter never executed gets a page saying so (:func:`_placeholder`), unless a chapter named reads
    every chapter's results (the summary), which executes it.

    **One plan for the build.** The chapters to execute run two at a time (:data:`AT_ONCE`). A chapter that asks
    for runs not trained yet writes them down and stops (``study.runs.schedule.ask``); its runs go at once to one
    pool of workers kept for the whole build (``workers``, 0: one per CPU; or the Dask ``scheduler``), on
    ``device``, in stacks, and the chapter runs again once they are trained, while the others go on. The runs that
    depend on earlier results (Table 1's configuration is the grid's winner) are asked for when it runs again. A chapter that completes has trained nothing itself. ``scheduler`` (a
    Dask scheduler's address) is also handed to every chapter with a ``scheduler`` parameter, outside its cache
    key; ``device`` is part of every chapter's key (the runs' keys name it). Stops at the first failing chapter with
    :class:`ChapterError`. Writes ``_build/executed/timings.json`` (the build's wall and process CPU
    seconds, each chapter's last execution, each wait for runs, the models the book's chapters train with their
    epochs and CPU time, :func:`plan_totals`) and merges the
    chapters' numbers into ``_build/results.json`` (:mod:`study.book.results`): before the chapters that run last
    (:func:`_runs_last`, such as a summary that reads them) and again at the end.
    """
    import nbformat

    root = Path(root).resolve()
    chs = chapters(root)
    stems = [c.stem for c in chs]
    unknown = [s for s in only or [] if s not in stems]
    if unknown:
        raise ConfigError(f"--only {', '.join(unknown)}: no such chapter; the chapters are: {', '.join(stems)}")
    injected = {"preset": preset}
    started = time.perf_counter()
    package = source_hash(words=True)
    timings: dict[str, dict[str, Any]] = {}
    stages: list[dict[str, Any]] = []
    steps: dict[str, float] = {}  # the builder's own steps after the chapters: their seconds
    done: list[tuple[Chapter, dict[str, Any], dict[str, Any], float]] = []
    sources = {ch.stem: _read_notebook(ch.source) for ch in chs}
    last = [ch for ch in chs if _runs_last(sources[ch.stem])]  # they read what the others wrote
    order = [ch for ch in chs if ch not in last] + last
    recommended = False  # made (or not needed): only then do the chapters it is made from keep their keys
    try:
        with tempfile.TemporaryDirectory(prefix="study-book-") as tmp:
            todo: list[tuple[int, Chapter, Path, dict[str, Any], dict[str, Any], dict[str, Any]]] = []
            for n, ch in enumerate(order, 1):
                where = f"[{n}/{len(chs)}] {ch.stem}"
                nb = sources[ch.stem]
                if not _is_notebook(nb):  # a plain page: placed, never executed
                    _copy_if_changed(ch.source, root / EXECUTED / f"{ch.entry}.md")
                    timings[ch.stem] = {"seconds": 0.0, "cached": True, "page": True}
                    continue
                probe = Path(tmp) / f"{ch.stem}.ipynb"
                nbformat.write(nb, probe)
                parameters = notebook_parameters(probe, injected)
                runtime = {k: v for k, v in {"scheduler": scheduler}.items() if v and k in parameters}
                parameters = {k: v for k, v in parameters.items() if k not in RUNTIME}
                base = {
                    "chapter": hashlib.sha256(ch.source.read_bytes()).hexdigest(),
                    "injected": canonical_json(injected),
                    "package": package,
                    "kernel": KERNEL,
                    **({"device": device} if device != "cpu" else {}),
                }
                current = key({**base, "inputs": inputs_fingerprint(root, parameters)}, length=64)
                action, stored = _decide(ch, current, force, only, reads_all=any(c.stem in (only or ()) for c in last))
                if action == "absent":
                    _placeholder(ch, only or [])
                    timings[ch.stem] = {"seconds": 0.0, "cached": True, "absent": True}
                    tqdm.write(f"{where}: not executed (never executed before; not in --only)", file=sys.stderr)
                    continue
                if action != "execute":
                    seconds = stored.get("seconds", 0.0)
                    timings[ch.stem] = {"seconds": seconds, "cached": True, **({"stale": True} if action == "kept" else {})}
                    note = f"executed earlier in {seconds:.1f} s" if action == "cached" else "out of date; not in --only"
                    tqdm.write(f"{where}: {action} ({note})", file=sys.stderr)
                    continue
                todo.append((n, ch, probe, nb, injected | runtime, {"base": base, "parameters": parameters}))
            _run_planned(root, preset, chs, last, todo, timings, stages, done, Path(tmp), scheduler, device, workers,
                         cache_dir(root, data_dir))
        if {ch.stem for ch, *_ in done} & RECOMMENDING:
            steps["recommended model"] = _recommend(preset, cache_dir(root, data_dir), device, _sweep_measured(root))
        recommended = True
    finally:
        # Keys again, once every chapter of this run has written what it writes: a chapter whose input folder a
        # later chapter adds to is not re-executed next time for that reason alone. Each was also written as its
        # chapter ended (but those the recommended model is made from), so a build killed before this point (a
        # session's end) executes again only those and what it had not done; those get no key from a build
        # stopped before the model was made (Ctrl-C), so the next one makes it.
        for ch, base, parameters, seconds in done:
            if _keyed_now(ch, recommended):
                _write_key(ch, base, parameters, root, seconds)
        if timings:
            record = {"preset": preset, "device": device, "wall_seconds": round(time.perf_counter() - started, 3),
                      "cpu_seconds": round(_cpu_seconds(), 3), "chapters": timings, "stages": stages, "steps": steps,
                      "runs": plan_totals(root),
                      "runs_by_chapter": cluster.plan_by_part([ch.plan_part for ch in chapters(root)]),
                      **cluster.plan_listed([ch.plan_part for ch in chapters(root)])}
            try:
                results.merge([ch.results_part for ch in chs], root / results.FILE, preset)
            finally:  # the timings are written even where the results cannot be merged
                record["render_cpu_seconds"] = _renders(root / results.FILE)
                write_text_atomic(root / EXECUTED / "timings.json", json.dumps(record, indent=1) + "\n")
    return timings


def _renders(path: Path) -> dict[str, float]:
    """CPU seconds each of the chapters' renders took (``study.report.usercamera.render_cpu``), as the results file at
    ``path`` holds them, by what was rendered (those it has: the clips are rendered once, so a resumed build's last
    process still reports them)."""
    from study.core.errors import StudyError
    from study.report.usercamera import render_cpu

    try:
        return render_cpu(results.load(path)) if path.is_file() else {}
    except StudyError:  # a record only: the results' own check reports a bad file where it is read for the book
        return {}


RECOMMENDING = {"realworld", "usercamera"}
"""The chapters whose runs the recommended model is chosen from: once one of them has executed, the build saves it."""


def _keyed_now(ch: Chapter, recommended: bool) -> bool:
    """Whether an executed chapter's key may be written now: any chapter's, but those the recommended model is made
    from only once it is made (``recommended``), so that a build stopped before never leaves them cached without it."""
    return recommended or ch.stem not in RECOMMENDING


def _sweep_measured(root: Path) -> dict[str, dict[str, Any]]:
    """What the camera sweep's chapter measured in its last run for each kind of model through each path (its
    results part; empty if it never ran)."""
    from study.report.usercamera import measured

    part = next(ch.results_part for ch in chapters(root) if ch.stem == "usercamera")
    return measured(results.load(part)) if part.is_file() else {}


def _recommend(preset: str, data: Path, device: str, measured: dict[str, dict[str, Any]]) -> float:
    """The builder's step after the chapters: the model ``study classify`` uses without ``--model``, chosen from the
    runs the chapters trained, with what the camera sweep ``measured``, saved in ``data``
    (``study.methods.recommend.make``: keyed, so an unchanged build rewrites nothing). Returns its seconds."""
    from study.methods import recommend
    from study.runs import Runner

    t0 = time.perf_counter()
    path = recommend.make(Runner.open(preset, 0, data, device=device), measured)
    tqdm.write(f"recommended model: {path}", file=sys.stderr)
    return round(time.perf_counter() - t0, 3)


def _cpu_seconds() -> float:
    """Process CPU time of this build: its own and that of its finished children (the kernels; the training
    workers), user and system."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def cache_dir(root: Path, data_dir: Path | None = None) -> Path:
    """The build's cache folder, absolute: ``data_dir``, else ``$STUDY_DATA_DIR``, else ``data/`` (a relative one
    under ``root``, where the chapters run)."""
    folder = datadir.resolve(data_dir)
    return folder if folder.is_absolute() else (root / folder).resolve()


AT_ONCE = 2
"""Chapters executed at the same time (each in its own kernel): on two cores one chapter computes while another
waits for its runs, and the runs train while the chapters that have not stopped go on."""


def _run_planned(root: Path, preset: str, chs: list[Chapter], last: list[Chapter], todo: list, timings: dict,
                 stages: list, done: list, tmp: Path, scheduler: str, device: str, workers: int, data: Path) -> None:
    """Execute the chapters of ``todo`` (see :func:`execute`), :data:`AT_ONCE` at a time. A chapter that stops at
    runs not trained yet hands them to one pool of workers kept for the whole build (``study.runs.schedule.Trainer``)
    and runs again once its own runs are trained, while the other chapters go on executing and training (the Bullet
    simulation and the renders overlap the first runs). Each such wait is a *stage* of ``stages``: the runs the
    chapter asked for, how many of them no other chapter had asked for first (``new``), and how long it waited. The chapters that run last wait until every other
    chapter is done."""
    from study.runs import (
        schedule,  # torch: only a build that executes a chapter loads it
    )

    def attempt(entry: tuple, pending: Path) -> tuple[str, float]:
        n, ch, probe, nb, params, _ = entry
        tqdm.write(f"[{n}/{len(chs)}] {ch.stem}: executing" + (" again" if tries[ch.stem] > 1 else ""),
                   file=sys.stderr)
        t0 = time.perf_counter()
        try:
            _execute(ch, probe, nb, params, root, pending=pending, device=device, data_dir=data)
        except _Pending:
            return "stopped", time.perf_counter() - t0
        except ChapterError:
            timings[ch.stem] = {**timings.get(ch.stem, {}), "seconds": round(time.perf_counter() - t0, 3),
                                "cached": False, "failed": True}
            raise
        return "executed", time.perf_counter() - t0

    tries: dict[str, int] = {}
    rest, final = [t for t in todo if t[1] not in last], [t for t in todo if t[1] in last]
    with schedule.Trainer(data, workers=workers or None, scheduler=scheduler or None, device=device,
                          progress=True) as trainer, ThreadPoolExecutor(AT_ONCE) as pool:
        for group in (rest, final):
            if group is final and final:  # the results of every other chapter, merged for them
                results.merge([c.results_part for c in chs], root / results.FILE, preset)
            ready = list(group)
            running: dict[Future, tuple[tuple, Path, set[str]]] = {}
            waiting: dict[str, tuple[tuple, list[Future], tuple[int, int], float]] = {}  # stem -> its runs training
            while ready or running or waiting:
                while ready and len(running) < AT_ONCE:
                    entry = ready.pop(0)
                    tries[entry[1].stem] = tries.get(entry[1].stem, 0) + 1
                    pending = tmp / f"pending-{entry[1].stem}-{tries[entry[1].stem]}.jsonl"
                    running[pool.submit(attempt, entry, pending)] = (entry, pending, trainer.trained())
                finished, _ = wait(_to_await(running, waiting), return_when=FIRST_COMPLETED)
                for stem, (entry, fs, n_runs, t0) in list(waiting.items()):
                    if all(f.done() for f in fs):
                        for f in fs:
                            f.result()  # a worker's error ends the build
                        del waiting[stem]
                        stages.append({"runs": n_runs[0], "new": n_runs[1], "chapters": [stem],
                                       "seconds": round(time.perf_counter() - t0, 3)})
                        ready.append(entry)
                for f in finished & running.keys():
                    entry, pending, before = running.pop(f)
                    ch, info, where = entry[1], entry[5], f"[{entry[0]}/{len(chs)}] {entry[1].stem}"
                    outcome, seconds = f.result()
                    if outcome == "executed":
                        done.append((ch, info["base"], info["parameters"], seconds))
                        if _keyed_now(ch, recommended=False):
                            with contextlib.suppress(OSError):  # an input another chapter moves: the end writes it
                                _write_key(ch, info["base"], info["parameters"], root, seconds)  # kept if killed
                        timings[ch.stem] = {**timings.get(ch.stem, {}), "seconds": round(seconds, 3), "cached": False}
                        tqdm.write(f"{where}: executed in {_duration(seconds)}", file=sys.stderr)
                        continue
                    entry_t = timings.setdefault(ch.stem, {"seconds": 0.0, "cached": False})
                    entry_t["waited"] = round(entry_t.get("waited", 0.0) + seconds, 3)  # its executions that stopped
                    jobs = schedule.pending(pending)
                    if not jobs or {schedule.run_key(ds, c, t, device) for ds, c, t in jobs} <= before:
                        raise ChapterError(
                            f"chapter {ch.stem} stopped for runs that "
                            + ("it did not name" if not jobs else "were trained before it ran: the chapter's kernel "
                               "computes other run keys than the builder (another study package, torch or device?)"))
                    n_before = len(trainer.futures)
                    fs = trainer.submit(jobs)
                    tqdm.write(f"{where}: stopped after {_duration(seconds)} for {len(jobs)} runs "
                               f"({len(trainer.futures) - n_before} new to train)", file=sys.stderr)
                    waiting[ch.stem] = (entry, fs, (len(jobs), len(trainer.futures) - n_before), time.perf_counter())


def _to_await(running: dict[Future, Any], waiting: dict[str, tuple]) -> set[Future]:
    """What the build loop waits on: the chapters executing and the runs the stopped ones wait for that are not
    done yet. A done future in the set would end every wait at once: the loop would spin, a core busy for nothing."""
    return set(running) | {f for _, fs, _, _ in waiting.values() for f in fs if not f.done()}


def plan_totals(root: Path) -> dict[str, float]:
    """The distinct models the book's chapters train (``models``), the process CPU seconds their records took
    (``cpu_seconds``) and their epochs (``epochs``), from each chapter's plan part
    (``study.runs.cluster.plan_totals``)."""
    return cluster.plan_totals([ch.plan_part for ch in chapters(root)])


def _duration(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.1f} s"
    whole = round(seconds)
    return f"{whole // 60} min {whole % 60} s"


def timings_table(timings: dict[str, dict[str, Any]], runs: dict[str, float] | None = None) -> str:
    """The table :func:`build` prints at the end: each chapter, whether it ran, and how long it took; with
    ``runs`` (:func:`plan_totals`), how many models the book trains and their CPU time."""
    width = max(len(s) for s in timings)
    lines = []
    for stem, t in timings.items():
        if t.get("page"):
            what = "page (copied)"
        elif t.get("failed"):
            what = f"FAILED after {_duration(t['seconds'])}"
        elif t.get("absent"):
            what = "not executed (not in --only; never executed before)"
        elif t["cached"]:
            what = f"cached (took {_duration(t['seconds'])} when executed)" + (", out of date" if t.get("stale") else "")
        else:
            what = f"executed in {_duration(t['seconds'])}"
        lines.append(f"  {stem:<{width}}  {what}")
    ran = sum(t["seconds"] for t in timings.values() if not t["cached"])
    lines = ["chapters:", *lines, f"  {'total':<{width}}  {_duration(ran)} executing this time"]
    if runs and runs.get("models"):
        lines.append(f"runs: {int(runs['models'])} models, {int(runs.get('epochs', 0))} epochs, "
                     f"{_duration(runs['cpu_seconds'])} of training (process CPU time, summed from their records)")
    return "\n".join(lines)


@contextlib.contextmanager
def _cluster(scheduler: str) -> Iterator[str]:
    """The scheduler address the chapters get: a ``LocalCluster`` started for this build when ``scheduler`` is
    'local' (closed at the end), else ``scheduler`` as it is."""
    if scheduler != "local":
        yield scheduler
        return
    with cluster.local_cluster(cluster.default_workers()) as local:
        tqdm.write(f"dask: a LocalCluster of {cluster.default_workers()} workers at {local.scheduler_address}",
                   file=sys.stderr)
        yield local.scheduler_address


def _stage(root: Path) -> Path:
    """Copy the files the Jupyter Book build reads beside the executed chapters; returns that folder."""
    out = root / EXECUTED
    for name in STAGED:
        src = root / name
        if not src.is_file():
            raise ConfigError(f"{src}: missing; the book needs it to build")
        _copy_if_changed(src, out / name)
    for name in STAGED_IF_PRESENT:
        if (root / name).is_file():
            _copy_if_changed(root / name, out / name)
    book = root / "book"
    for src in sorted(p for p in book.rglob("*") if p.is_file()) if book.is_dir() else []:
        rel = src.relative_to(root)
        if src.suffix == ".md" or ".ipynb_checkpoints" in rel.parts or "__pycache__" in rel.parts:
            continue  # chapters and pages are placed by execute()
        _copy_if_changed(src, out / rel)
    return out


def _copy_if_changed(src: Path, dst: Path) -> None:
    if dst.is_file() and dst.read_bytes() == src.read_bytes():
        return  # keep the old mtime
    dst.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(src, dst)


def _jupyter_book() -> list[str]:
    exe = Path(sys.executable).parent / "jupyter-book"
    return [str(exe)] if exe.is_file() else [sys.executable, "-m", "jupyter_book"]


def render_html(root: Path) -> Path:
    """Render the executed book to ``<root>/_build/html`` (execution off, warnings are errors)."""
    root = Path(root).resolve()
    src = _stage(root)
    # --all: a page left unchanged would otherwise not repeat its warnings, and -W would pass.
    cmd = [*_jupyter_book(), "build", str(src), "--path-output", str(root), "--all", "-W", "-n", "--keep-going", "-q"]
    sys.stderr.flush()
    proc = subprocess.run(cmd, cwd=root, stdout=2)  # its log to stderr: stdout is left for the index path
    if proc.returncode != 0:
        raise ChapterError(
            f"jupyter-book build failed (exit {proc.returncode}) on {src.relative_to(root)}; "
            "see the warnings above (every warning is an error)"
        )
    return root / "_build" / "html"


def build(root: Path, preset: str, force: bool, only: list[str] | None, html: bool, scheduler: str = "",
          device: str = "cpu", data_dir: Path | None = None) -> None:
    """Execute the chapters of the book at ``root`` with ``preset`` (cached, their runs planned and trained
    together: :func:`execute`), then, if ``html``, render it.

    ``scheduler``: '' trains on a local process pool; 'local' starts one Dask ``LocalCluster`` for the whole build
    (loopback only, one single-threaded worker per core); anything else is the address of a Dask scheduler the
    runs are sent to. ``device``: 'cpu', 'cuda', or 'auto' (a GPU where there is one, said on the terminal). The
    executed copies land in ``<root>/_build/executed/book/``, their timings in ``_build/executed/timings.json``, and
    the HTML in ``<root>/_build/html``.
    """
    presets.check(preset)
    root = Path(root).resolve()
    if not root.is_dir():
        raise ConfigError(f"--root {root}: no such folder")
    check_writable(root / EXECUTED / "timings.json", "book output folder")
    check_writable(cache_dir(root, data_dir) / "README", "cache folder (--data-dir or $STUDY_DATA_DIR)")
    chosen = cluster.device(device)
    if device == "auto":
        tqdm.write(f"device: {chosen}" + (" (a GPU is at hand)" if chosen != "cpu" else " (no GPU here)"), file=sys.stderr)
    with _cluster(scheduler) as address:
        timings = execute(root, preset, force=force, only=only, scheduler=address, device=chosen, data_dir=data_dir)
    print(timings_table(timings, plan_totals(root)), file=sys.stderr)
    record = root / EXECUTED / "timings.json"
    kept = json.loads(record.read_text()) if record.is_file() else {}
    failed, unsettled = kept.get("failed_runs", []), kept.get("unsettled_runs", [])
    if unsettled:
        print(f"runs still improving when their epoch budget ran out (not flattened): {len(unsettled)} "
              f"({EXECUTED}/timings.json, 'unsettled_runs')", file=sys.stderr)
    if failed:
        chance = len(failures.by_chance(failed))
        print(f"failed runs: {len(failed)}, {len(failed) - chance} of them designed to fail, {chance} by chance "
              f"(each with its reason: {EXECUTED}/timings.json, 'failed_runs')", file=sys.stderr)
    if html:
        index = render_html(root) / "index.html"
        print(f"the book: {index}", file=sys.stderr)
        print(index)
