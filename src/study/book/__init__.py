"""The book: the builder that executes each chapter with papermill and renders them with Jupyter Book, what it
does to an executed chapter (``nbtidy``), the build's results file with its verdicts (``results``), and the
helpers the chapters share for figures and tables (``figures``, ``tables``).

``study.book.build(root, preset, ...)`` is what ``study book`` and ``make book`` run.
"""

from study.book.builder import (
    EXECUTED,
    FAILED,
    Chapter,
    build,
    chapters,
    execute,
    inputs_fingerprint,
    notebook_parameters,
    plan_totals,
    render,
    summary,
)

__all__ = ["EXECUTED", "FAILED", "Chapter", "build", "chapters", "execute", "inputs_fingerprint",
           "notebook_parameters", "plan_totals", "render", "summary"]
