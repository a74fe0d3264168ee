"""Which runs the book means to fail, and why: a run that ends on its initial plateau is either one of these, shown
failing on purpose, or a failure by chance that the build must show and explain. No torch needed (the builder reads
it to list a build's failed runs in its timings, :func:`failed_runs`).
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


def failed_runs(planned: Mapping[str, tuple[str, Path]]) -> list[dict[str, Any]]:
    """Every failed run of a build's plan (model key -> (its record's path, the chapter's plan file)), each with the
    chapter that first asked for it, what it is and :func:`reason`; a record that cannot be read is left out."""
    out = []
    for model, (record, part) in planned.items():
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            rec = json.loads(Path(record).read_text())
            if not rec.get("failed"):
                continue
            c = rec["config"]
            out.append({"chapter": part.stem, "model": model, "dims": c["dims"], "length": c["length"],
                        "cell": c["cell"], "inputs": c["inputs"], "observe": c["observe"], "seed": c["seed"],
                        "best_epoch": rec.get("best_epoch"), "epochs_run": rec.get("epochs_run"),
                        "reason": reason(c)})
    return out


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


def unsettled_runs(planned: Mapping[str, tuple[str, Path]]) -> list[dict[str, Any]]:
    """Every run of a build's plan (model key -> (its record's path, the chapter's plan file)) that had not flattened
    (:func:`unsettled`), each with the chapter that first asked for it and what it is; unreadable records left out."""
    out = []
    for model, (record, part) in planned.items():
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            rec = json.loads(Path(record).read_text())
            if unsettled(rec):
                c = rec["config"]
                out.append({"chapter": part.stem, "model": model, "dims": c["dims"], "length": c["length"],
                            "cell": c["cell"], "inputs": c["inputs"], "observe": c["observe"], "lr": c["lr"],
                            "truncation": c["truncation"], "seed": c["seed"], "best_epoch": rec["best_epoch"],
                            "epochs": c["epochs"], "val_accuracy": rec.get("val_accuracy")})
    return out


def by_chance(failed: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """The runs of :func:`failed_runs` that were not designed to fail."""
    return [f for f in failed if f["reason"] == BY_CHANCE]
