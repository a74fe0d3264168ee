"""The learners the chapters compare, each defined once: its key in the results, its words in the book, what kind
of learner it is and the chapters that compare it. No torch needed.

Every other list of learners is derived from :data:`LEARNERS`: each chapter's typed keys (``study.report.motion.
Learner``, ``study.report.engine.Learner``, ``study.report.baselines.Method``), their words in the tables and the
summary (:data:`WORDS`). ``tests/test_learners_once.py`` checks that what the chapters produce is what is named here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

Kind = Literal["network", "exact-trained network", "minirocket", "physics", "rule"]
"""How a learner is built (``study.methods.learners``: Network, Rocket, Physics, Rule)."""
Chapter = Literal["motion", "engine", "baselines"]


@dataclass(frozen=True)
class Learner:
    """One learner a chapter compares."""

    key: str
    """Its name in the results file (``motion.<key>.air_on.exact``)."""
    words: str
    """What the book calls it."""
    kind: Kind
    chapters: tuple[Chapter, ...]
    """The chapters that compare it."""


LEARNERS: tuple[Learner, ...] = (
    Learner("peephole_positions", "peephole LSTM, positions (the paper's)", "network", ("motion", "engine")),
    Learner("peephole_velocity", "peephole LSTM, with velocity", "network", ("motion", "engine")),
    Learner("gru_velocity", "GRU, with velocity", "network", ("motion",)),
    Learner("peephole_exact_trained", "peephole LSTM, positions, trained exact", "exact-trained network", ("motion",)),
    Learner("peephole", "peephole LSTM (paper)", "network", ("baselines",)),
    Learner("gru", "GRU", "network", ("baselines",)),
    Learner("minirocket", "MiniRocket, positions", "minirocket", ("motion", "engine", "baselines")),
    Learner("physics", "physics baseline", "physics", ("motion", "baselines")),
    Learner("rule", "best one-feature rule", "rule", ("motion", "engine", "baselines")),
)
"""Every learner, in the order the tables list them."""

WORDS: dict[str, str] = {q.key: q.words for q in LEARNERS}
"""Each learner's key -> its words."""


def keys(chapter: Chapter, *kinds: Kind) -> tuple[str, ...]:
    """The keys of the learners ``chapter`` compares (of ``kinds`` only, where given), in table order."""
    return tuple(q.key for q in LEARNERS if chapter in q.chapters and (not kinds or q.kind in kinds))
