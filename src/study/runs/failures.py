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
SHORT_INPUT = 0.5
"""Seconds: the length chapter's shortest input (the paper preset's first length), which ends about when the throws
first touch the floor."""


@dataclass(frozen=True)
class Designed:
    """A kind of run the book shows failing on purpose."""

    reason: str
    """Why, in words: the experiment that shows it."""
    applies: Callable[[Mapping[str, Any], float | None], bool]
    """Whether a run's config (``TrainConfig`` as a dict) at the data's frame rate (fps; None: not recorded) is of
    this kind."""


def _truncated(c: Mapping[str, Any], fps: float | None) -> bool:
    """Whether back-propagation stopped short of the input's first frames (truncation below the input's frames)."""
    return (fps is not None and c.get("loss_at", "last") == "last"
            and int(c.get("truncation", 0)) < round(float(c.get("length", 0.0)) * fps))


DESIGNED: tuple[Designed, ...] = (
    Designed("Table 1's first protocol: no forget bias and no minimum of epochs, the initial plateau it shows",
             lambda c, fps: c.get("forget_bias") == 0.0 and c.get("min_epochs") == 0),
    Designed("Table 1's protocol comparison: the first builds' early stop, with no minimum of epochs",
             lambda c, fps: c.get("min_epochs") == 0),
    Designed(f"the length chapter: a constant forget bias over {LONG_INPUT:g} s, the paper's Figure 4 drop",
             lambda c, fps: c.get("forget_init") == "constant" and float(c.get("length", 0.0)) >= LONG_INPUT),
    Designed(f"the length chapter's shortest input ({SHORT_INPUT:g} s), over about when the throws first touch the "
             "floor: too short to hold a pattern to learn, the paper's explanation of Figure 4's left end",
             lambda c, fps: float(c.get("length", 0.0)) <= SHORT_INPUT),
    Designed("truncated back-propagation: the gradient stops short of the input's first frames, the handicap the grid's "
             "short truncation and the long-input test measure (such runs leave the plateau late or never)",
             _truncated),
)
"""Every kind of run the book means to fail, the first that applies naming the reason."""

BY_CHANCE = "not designed to fail: a failure by chance, to explain"
REJECTED = "a candidate its chapter's validation turned down (a grid's rate not chosen): it counts in no result"


def reason(config: Mapping[str, Any], fps: float | None = None) -> str:
    """Why a run of ``config`` on data at ``fps`` (None: not recorded) that failed was meant to (:data:`DESIGNED`), or
    :data:`BY_CHANCE`."""
    return next((d.reason for d in DESIGNED if d.applies(config, fps)), BY_CHANCE)


LAST = 10
"""Epochs at the end of a run over which settling is measured."""
SETTLED = 2.0
"""Points: the most the validation accuracy may move over the last :data:`LAST` epochs of a settled run."""
CLIMB = 1.0
"""Points: the most the validation accuracy may still rise from the :data:`LAST` epochs before the last ones to the
last ones (means) in a settled run: a smooth curve that still climbs has not flattened."""


def swing_and_climb(accuracies: Sequence[float]) -> tuple[float, float]:
    """(swing, climb) of a validation-accuracy curve (fractions, one per epoch), points: its range over the last
    :data:`LAST` epochs, and the rise of their mean over the mean of the :data:`LAST` before (0 where there are not
    enough epochs)."""
    a = [100 * float(v) for v in accuracies]
    last, before = a[-LAST:], a[-2 * LAST:-LAST]
    swing = max(last) - min(last) if last else 0.0
    climb = sum(last) / len(last) - sum(before) / len(before) if last and before else 0.0
    return swing, climb


def unsettled(record: Mapping[str, Any]) -> bool:
    """Whether a run record's network had not flattened when its epoch budget ran out: it ran the whole budget and
    its validation accuracy still swung more than :data:`SETTLED` or climbed more than :data:`CLIMB` points over the
    last :data:`LAST` epochs (``benchmarks/bench_recipe.py``'s rule). A run that stopped early had flattened by the
    patience rule; a fixed budget ('cosine', no early stopping) is judged by its own schedule, not here."""
    c = record["config"]
    if c.get("lr_schedule") == "cosine" or record.get("epochs_run") is None or not record.get("history"):
        return False
    if int(record["epochs_run"]) < int(c["epochs"]):
        return False
    swing, climb = swing_and_climb([e["val_accuracy"] for e in record["history"]])
    return swing > SETTLED or climb > CLIMB


def listed(planned: Mapping[str, tuple[str, Path]], rejected: frozenset[str] = frozenset(),
           ) -> dict[str, list[dict[str, Any]]]:
    """One pass over a build's plan (model key -> (its record's path, the chapter's plan file)): ``failed_runs``,
    every failed run with its reason (:func:`reason`'s designed one, else :data:`REJECTED` for a model in
    ``rejected``, else :data:`BY_CHANCE`), and
    ``unsettled_runs``, every run still improving at its budget (:func:`unsettled`); each with the chapter that
    first asked for it and what it is. A record that cannot be read is left out."""
    out: dict[str, list[dict[str, Any]]] = {"failed_runs": [], "unsettled_runs": []}
    for model, (record, part) in planned.items():
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            rec = json.loads(Path(record).read_text())
            c = rec["config"]
            row = {"chapter": part.stem, "model": model,
                   **{k: c[k] for k in ("dims", "length", "cell", "inputs", "observe", "lr", "truncation", "seed")},
                   **{k: rec.get(k) for k in ("best_epoch", "epochs_run", "val_accuracy")}}
            if rec.get("failed"):
                why = reason(c, rec.get("fps"))
                why = REJECTED if why == BY_CHANCE and model in rejected else why
                out["failed_runs"].append({**row, "reason": why})
            if unsettled(rec):
                out["unsettled_runs"].append(row)
    return out


def by_chance(failed: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """The failed runs of :func:`listed` that were not designed to fail."""
    return [f for f in failed if f["reason"] == BY_CHANCE]
