"""Which runs the book means to fail, and why: a run that ends on its initial plateau is either one of these, shown
failing on purpose, or a failure by chance that the build must show and explain. No torch needed (the builder reads
it to list a build's failed runs in its timings, :func:`listed`, beside the runs still improving at their budget).
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

LONG_INPUT = 6.0
"""Seconds: the length chapter's longest input (the paper preset's ``long_lengths``), where a constant forget bias
is the paper's Figure 4 drop."""


@dataclass(frozen=True)
class Designed:
    """A kind of run the book shows failing on purpose."""

    reason: str
    """Why, in words: the experiment that shows it."""
    applies: Callable[[Mapping[str, Any]], bool]
    """Whether a run's config (``TrainConfig`` as a dict) is of this kind."""


DESIGNED: tuple[Designed, ...] = (
    Designed("Table 1's first protocol: no forget bias and no minimum of epochs, the initial plateau it shows",
             lambda c: c.get("forget_bias") == 0.0 and c.get("min_epochs") == 0),
    Designed("Table 1's protocol comparison: the first builds' early stop, with no minimum of epochs",
             lambda c: c.get("min_epochs") == 0),
    Designed(f"the length chapter: a constant forget bias over {LONG_INPUT:g} s, the paper's Figure 4 drop",
             lambda c: c.get("forget_init") == "constant" and float(c.get("length", 0.0)) >= LONG_INPUT),
)
"""Every kind of run the book means to fail, the first that applies naming the reason."""

BY_CHANCE = "not designed to fail: a failure by chance, to explain"


def reason(config: Mapping[str, Any]) -> str:
    """Why a run of ``config`` that failed was meant to (:data:`DESIGNED`), or :data:`BY_CHANCE`."""
    return next((d.reason for d in DESIGNED if d.applies(config)), BY_CHANCE)


SETTLE_EPOCHS = 10
"""A run that could stop early but ran its whole epoch budget with its best epoch among the last this many had not
flattened: its validation loss was still falling when the budget ran out."""


def unsettled(record: Mapping[str, Any]) -> bool:
    """Whether a run record's network was still improving when its epoch budget ran out (:data:`SETTLE_EPOCHS`); a
    fixed budget ('cosine', no early stopping) is judged by its own schedule, not here."""
    c = record["config"]
    if c.get("lr_schedule") == "cosine" or record.get("epochs_run") is None or record.get("best_epoch") is None:
        return False
    return int(record["epochs_run"]) >= int(c["epochs"]) and int(record["best_epoch"]) >= int(c["epochs"]) - SETTLE_EPOCHS


def listed(planned: Mapping[str, tuple[str, Path]]) -> dict[str, list[dict[str, Any]]]:
    """One pass over a build's plan (model key -> (its record's path, the chapter's plan file)): ``failed_runs``,
    every failed run with :func:`reason`, and ``unsettled_runs``, every run still improving at its budget
    (:func:`unsettled`); each with the chapter that first asked for it and what it is. A record that cannot be read
    is left out."""
    out: dict[str, list[dict[str, Any]]] = {"failed_runs": [], "unsettled_runs": []}
    for model, (record, part) in planned.items():
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            rec = json.loads(Path(record).read_text())
            c = rec["config"]
            row = {"chapter": part.stem, "model": model,
                   **{k: c[k] for k in ("dims", "length", "cell", "inputs", "observe", "lr", "truncation", "seed")},
                   **{k: rec.get(k) for k in ("best_epoch", "epochs_run", "val_accuracy")}}
            if rec.get("failed"):
                out["failed_runs"].append({**row, "reason": reason(c)})
            if unsettled(rec):
                out["unsettled_runs"].append(row)
    return out


def by_chance(failed: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """The failed runs of :func:`listed` that were not designed to fail."""
    return [f for f in failed if f["reason"] == BY_CHANCE]
