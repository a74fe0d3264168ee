"""Scores carry every seed's p(heavy) (methods.learners.Scores): the label is heavy above 1/2, and every learner
answers through them -- a network its softmax (at every frame when asked), the physics baseline its logistic, a
rule 0 or 1."""

from __future__ import annotations

import numpy as np

from study.methods import learners
from study.runs import stats


class Fixed:
    """A model whose p(heavy) is given, for every input."""

    def __init__(self, p: np.ndarray) -> None:
        self.p = np.asarray(p, float)

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        return np.column_stack([1 - self.p, self.p])

    def predict_proba_frames(self, x: np.ndarray) -> np.ndarray:
        p = np.repeat(self.p[:, None], 4, axis=1)
        p[:, 0] = 0.5
        return np.stack([1 - p, p], axis=-1)


def test_a_label_is_heavy_above_one_half_and_correct_compares_it_with_the_truth():
    x, y = np.zeros((4, 3, 3)), np.array([0, 1, 1, 0])
    p = stats.probabilities([Fixed([0.2, 0.9, 0.5, 0.7]), Fixed([0.1, 0.6, 0.8, 0.3])], x)
    assert p.shape == (2, 4)
    s = learners.Scores({"t": p}, {"t": y})
    assert s.correct["t"].tolist() == [[True, True, False, False], [True, True, True, True]], "1/2 is light"
    assert (s.correct["t"] == stats.correct_of([Fixed(p[0]), Fixed(p[1])], x, y)).all()


def test_every_frame_answers_keep_their_frames_and_are_scored_at_the_last():
    x, y = np.zeros((2, 4, 3)), np.array([1, 0])
    p = stats.probabilities([Fixed([0.9, 0.2])], x, frames=True)
    assert p.shape == (1, 2, 4) and (p[:, :, 0] == 0.5).all()
    assert learners.Scores({"t": p}, {"t": y}).correct["t"].tolist() == [[True, True]]
