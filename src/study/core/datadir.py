"""Where the caches live: data sets, run records and models, videos, the tracker's measured error.

By default ``data/`` under the folder a command runs in (the project's root for ``make book``). A build can keep
them anywhere else, so that a checkout that changes every model can be built, read and compared beside another's,
and a later build resumes from the same caches: ``study book --data-dir DIR``, or ``STUDY_DATA_DIR=DIR`` for every
command. Inside a chapter executed by ``study book``, the build's folder comes with the chapter's ticket
(``study.core.ticket``).
"""

from __future__ import annotations

import os
from pathlib import Path

from study.core import ticket

ENV = "STUDY_DATA_DIR"
"""Environment variable naming the cache folder for every command (a user's setting; ``--data-dir`` wins)."""
DEFAULT = Path("data")
"""The cache folder when nothing else is said: ``data/`` under the current folder."""


def resolve(given: str | Path | None = None) -> Path:
    """The cache folder: ``given`` where it is not empty; else the build's (the chapter's ticket); else
    ``$STUDY_DATA_DIR``; else :data:`DEFAULT`."""
    for choice in (given, ticket.current().data_dir, os.environ.get(ENV)):
        if choice:
            return Path(choice).expanduser()
    return DEFAULT
