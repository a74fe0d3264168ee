"""Progress of long work, on the terminal of whoever waits for it: a tqdm bar, and a line per update in a
progress file when the book builder asks for one.

A chapter runs in a papermill kernel whose output goes into the notebook, not to the terminal. The
builder (``study.book``) therefore names a file for each chapter in its ticket (``study.core.ticket``) and
follows it; the
package's long loops (simulation, training runs, renders) report each step with :class:`Progress`,
which writes one JSON line per update there: ``{"stage", "done", "total", "note"}``, and the
builder shows them with a :class:`Follower`.
"""

from __future__ import annotations

import json
import os
import sys
import threading
from pathlib import Path
from types import TracebackType
from typing import TextIO

from tqdm import tqdm

from study.core import ticket


class Progress:
    """``with Progress("grid (Z)", total=16, note="3 cached") as p: ... p.update()`` -- a tqdm bar (if
    ``show``) and, where the chapter's ticket names a progress file, one JSON line per update appended to it."""

    def __init__(self, stage: str, total: int, *, show: bool = True, note: str = "", unit: str = "it") -> None:
        self.stage, self.total, self.note, self.done = stage, int(total), note, 0
        self.bar = tqdm(total=total, desc=stage, unit=unit, disable=not show, leave=False)
        self.path = ticket.current().progress or None
        self.id = f"{os.getpid()}.{id(self)}"  # two stages of the same name are two bars
        self._emit()

    def _emit(self) -> None:
        if self.path is None:
            return
        line = json.dumps({"stage": self.stage, "id": self.id, "done": self.done, "total": self.total, "note": self.note})
        try:
            with open(self.path, "a") as f:
                f.write(line + "\n")
        except OSError:
            self.path = None  # a progress file that cannot be written must not stop the work

    def update(self, n: int = 1) -> None:
        """Count ``n`` more steps done."""
        self.done += n
        self.bar.update(n)
        self._emit()

    def close(self) -> None:
        self.bar.close()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.close()


class Follower:
    """The builder's end of the channel: follows a progress file in a thread and shows each stage as a
    tqdm bar on ``file`` (stderr), prefixed with ``label`` (the chapter), until :meth:`stop`.

    ``with Follower(path, "table1"): run_the_kernel()``. The bar's time estimate is tqdm's, from the
    rate of the steps done so far in the stage.
    """

    def __init__(self, path: str | os.PathLike, label: str, file: TextIO | None = None, poll: float = 0.5) -> None:
        self.path, self.label, self.poll = Path(path), label, poll
        self.file = file if file is not None else sys.stderr
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._bar: tqdm | None = None
        self._stage: tuple[str, str] | None = None
        self._offset = 0

    def __enter__(self) -> Follower:
        self.path.unlink(missing_ok=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def stop(self) -> None:
        """Read what is left, close the bar, end the thread."""
        self._stop.set()
        self._thread.join()
        self._read()
        self._close_bar()

    def _run(self) -> None:
        while not self._stop.wait(self.poll):
            self._read()

    def _read(self) -> None:
        try:
            with open(self.path) as f:
                f.seek(self._offset)
                text = f.read()
        except OSError:
            return
        complete = text[: text.rfind("\n") + 1]  # a line still being written waits for the next read
        self._offset += len(complete)
        for line in complete.splitlines():
            try:
                msg = json.loads(line)
                self._show(str(msg["stage"]), str(msg.get("id", "")), int(msg["done"]), int(msg["total"]),
                           str(msg.get("note", "")))
            except (ValueError, KeyError, TypeError):
                continue

    def _show(self, stage: str, ident: str, done: int, total: int, note: str) -> None:
        if (stage, ident) != self._stage:
            self._close_bar()
            self._stage = (stage, ident)
            if total == 0:
                tqdm.write(f"{self.label} · {stage}: nothing to do{f' ({note})' if note else ''}", file=self.file)
                return
            self._bar = tqdm(total=total, desc=f"{self.label} · {stage}", file=self.file, dynamic_ncols=True,
                             mininterval=1.0)
        if self._bar is not None:
            if note:
                self._bar.set_postfix_str(note, refresh=False)
            self._bar.update(done - self._bar.n)

    def _close_bar(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
