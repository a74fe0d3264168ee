"""The training protocols Table 1's chapter compares, each defined once: its key in the results, its words in the
book, and what it changes from the study's protocol (``TrainConfig``'s defaults). No torch needed.

Each protocol adds one change to the one before it, up to the study's own; the last adds one more that the study
does not keep. Everything else -- the runs' configs (``study.runs.paper.protocol_plan``), the results' names
(:data:`ProtocolKey`), the chapter's table and the summary -- is derived from :data:`PROTOCOLS`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal


@dataclass(frozen=True)
class Protocol:
    """One training protocol."""

    key: str
    """Its name in the results file (``table1.protocol.<key>.<dims>``)."""
    words: str
    """What the book calls it."""
    changes: Mapping[str, Any] = field(default_factory=dict)
    """The ``TrainConfig`` fields it sets otherwise than the study's protocol."""
    first_stop: bool = False
    """Stops early as the first builds did: no minimum, the preset's ``first_patience`` and ``first_epochs``."""
    study: bool = False
    """The protocol every other experiment uses."""

    def fields(self, first_patience: int, first_epochs: int) -> dict[str, Any]:
        """The config fields it changes, the first builds' early stop filled in from a preset's values (no minimum,
        and a run on the plateau stops after its patience)."""
        first = ({"min_epochs": 0, "epochs": first_epochs, "patience": first_patience, "plateau_epochs": first_patience}
                 if self.first_stop else {})
        return {**self.changes, **first}


_RAW = {"average": "none"}  # the optimiser's own weights, validated and kept

PROTOCOLS: tuple[Protocol, ...] = (
    Protocol("first", "paper's network, our first protocol", {"forget_bias": 0.0, "clip_norm": 0.0, **_RAW}, True),
    Protocol("forget_bias", "+ forget bias 1 (the paper's TensorFlow default)", {"clip_norm": 0.0, **_RAW}, True),
    Protocol("min_epochs", "+ early stopping after a minimum, higher cap", {"clip_norm": 0.0, **_RAW}),
    Protocol("clipping", "+ gradient clipping (norm 1)", _RAW),
    Protocol("average", "+ weights averaged (EMA): the study's protocol", {}, study=True),
    Protocol("plateau", "+ learning rate halved when validation stalls", {"lr_schedule": "plateau"}),
)
"""Every protocol, in the order each adds its change."""

STUDY: Protocol = next(p for p in PROTOCOLS if p.study)
"""The study's protocol."""

BY_KEY: dict[str, Protocol] = {p.key: p for p in PROTOCOLS}

ProtocolKey = Literal[tuple(p.key for p in PROTOCOLS)]  # type: ignore[valid-type]
"""A protocol's key (read back from the results by these names)."""
