"""The ticket: everything the book's builder tells a chapter's kernel, and where the chapter answers, in one file.

``study book`` executes each chapter in its own papermill kernel, whose output goes into the notebook. Before it
starts one, it writes the chapter a :class:`Ticket` (a JSON file) and names it in the one environment variable
:data:`ENV`; inside the kernel, :func:`current` reads it (once per version of the file). The ticket says

- where the chapter's progress lines go (``study.core.progress``), its numbers (``study.book.results``) and the
  runs it was asked for (``study.runs.schedule.Plan``);
- the torch device its runs train on, and the build's cache folder;
- in a build that trains every chapter's runs together, the file where the chapter lists the runs it needs that
  are not trained yet (``study.runs.schedule.ask``) before it stops: the builder reads that file, not the
  exception, to tell a chapter that waits for runs from one that failed (:meth:`Ticket.asked`).

Outside a build there is no ticket: :func:`current` gives :data:`NONE`, and a chapter trains what it needs itself.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
from dataclasses import dataclass
from pathlib import Path

ENV = "STUDY_TICKET"
"""Environment variable naming the chapter's ticket file (set by ``study book``); unset outside a build."""


@dataclass(frozen=True)
class Ticket:
    """What the builder tells one execution of one chapter."""

    chapter: str = ""
    """The chapter it was written for (``data``, ``tutorial``, ...): another chapter executed inside that one's
    kernel (the tutorial re-runs the data chapter through papermill) inherits the environment, not the ticket's
    results file ('' : any)."""
    progress: str = ""
    """File the chapter's progress lines are appended to ('' : none)."""
    results: str = ""
    """File the chapter's numbers are written to ('' : none)."""
    plan: str = ""
    """File the chapter's runs are listed in, for the build's count of models ('' : none)."""
    pending: str = ""
    """File the chapter lists the runs it needs that are not trained yet, before it stops ('' : it trains them)."""
    device: str = ""
    """The torch device its runs train on ('' : the CPU, or what the chapter asks for)."""
    data_dir: str = ""
    """The build's cache folder ('' : the chapter's own default, ``study.core.datadir``)."""

    def write(self, path: str | Path) -> Path:
        """Write the ticket to ``path`` (a JSON file) and return it."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(dataclasses.asdict(self), indent=1) + "\n")
        return path

    def asked(self) -> bool:
        """Whether the chapter listed runs not trained yet (and so stopped for them, not for a failure)."""
        return bool(self.pending) and Path(self.pending).is_file() and Path(self.pending).stat().st_size > 0


NONE = Ticket()
"""No builder: nothing to write, the chapter trains what it needs itself."""


def current() -> Ticket:
    """The ticket :data:`ENV` names, or :data:`NONE` outside a build (or where the file cannot be read)."""
    path = os.environ.get(ENV)
    if not path:
        return NONE
    try:
        st = os.stat(path)
    except OSError:
        return NONE
    return _read(path, st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=16)
def _read(path: str, mtime_ns: int, size: int) -> Ticket:
    try:
        fields = json.loads(Path(path).read_text())
        return Ticket(**{f.name: str(fields.get(f.name, "")) for f in dataclasses.fields(Ticket)})
    except (OSError, ValueError, TypeError):
        return NONE
