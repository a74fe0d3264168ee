"""The book: the builder that executes each chapter with papermill and renders them with Jupyter Book, what it
does to an executed chapter (``nbtidy``), the build's results file (``results``), the one call that hands a
chapter's typed result to its page and to that file (``publish``), the summary page read from it (``summary``),
the introduction's software table (``software``) and the book's figure style (``figures``).

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
    render_html,
    timings_table,
)

__all__ = ["EXECUTED", "FAILED", "Chapter", "build", "chapters", "execute", "inputs_fingerprint",
           "notebook_parameters", "plan_totals", "render_html", "timings_table"]
