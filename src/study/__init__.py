"""Can a car tell a must-avoid object from a safe-to-pass one by its motion alone?

A reproduction of Fathollahi & Kasturi, arXiv:1609.00361, as a package in three layers and a top:

- ``study.simulate``: MuJoCo trajectories of light (bouncy) and heavy (sliding) objects, the dataset
  file, physics checks and measurements on trajectories.
- ``study.learn``: the paper's peephole LSTM (with its compiled time loops), training, evaluation,
  frame-by-frame streaming and a physics baseline.
- ``study.see``: video files, MuJoCo renders with ground truth, and the colour tracker.
- On top: ``study.runs`` (training what chapters ask for, cached), ``study.methods`` (what two or more
  chapters share: learners, camera conditions, the tracker's error), ``study.report`` (verdicts, numbers,
  tables), ``study.chapters`` (one module per page of the book), ``study.book`` (papermill and Jupyter Book)
  and ``study.cli`` (the command).

Every module is imported on demand, so ``import study`` stays cheap, and the modules users reach for
have short names: ``from study import synth, train, track`` is ``study.simulate.synth`` and so on.

The public API (``__all__``, the book's reference page): simulate a data set (:func:`dataset`, :class:`SynthConfig`,
:class:`ClassPrior`), train and evaluate (:class:`TrainConfig`, :func:`fit`, :func:`evaluate`), save and load
(:func:`load`, :func:`load_dataset`, :func:`save_dataset`), track a video (:func:`track_video`, :func:`read_csv`) and
answer light or heavy for a video or a track (:func:`classify`), and the book's experiments (:class:`Runner`)::

    import study

    ds = study.dataset("smoke", seed=0)
    model = study.fit(ds, study.TrainConfig(length=1.0, epochs=5))
    print(study.evaluate(model, ds.test)["accuracy"])
"""

import importlib
import os

# Headless rendering by default: MuJoCo reads MUJOCO_GL when it is first imported, which any submodule
# may do (set MUJOCO_GL=osmesa, or glfw with a display, before importing study to choose otherwise).
os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"

CLASSES: tuple[str, str] = ("light", "heavy")
"""Class names by label: 0 = light (bounces; safe to pass over), 1 = heavy (slides; must avoid)."""

SHORT_NAMES: dict[str, str] = {
    **{m: f"study.simulate.{m}" for m in ("scene", "contact", "synth", "data", "checks", "measure", "observe")},
    **{m: f"study.learn.{m}" for m in ("config", "metrics", "model", "native", "gru", "train", "stream", "baseline",
                                        "rocket")},
    **{m: f"study.see.{m}" for m in ("video", "render", "track")},
    **{m: f"study.chapters.{m}" for m in ("cues", "realworld", "decision", "table1", "motion", "length", "engine",
                                          "baselines")},
    "decide": "study.chapters.decision",
    **{m: f"study.report.{m}" for m in ("verdicts", "text")},
    **{m: f"study.book.{m}" for m in ("results", "figures", "publish")},
}
"""``study.<short>`` -> the module it names, for ``from study import synth`` and friends."""


EXPORTS: dict[str, str] = {
    "SynthConfig": "study.simulate.config", "ClassPrior": "study.simulate.config", "dataset": "study.simulate.synth",
    "Dataset": "study.simulate.data", "Split": "study.simulate.data",
    "load_dataset": "study.simulate.data:load", "save_dataset": "study.simulate.data:save",
    "TrainConfig": "study.learn.config", "fit": "study.learn.train", "evaluate": "study.learn.train",
    "load": "study.learn.trained", "TrainedModel": "study.learn.trained", "Ensemble": "study.learn.trained",
    "TrackConfig": "study.see.config", "track_video": "study.see.track", "read_csv": "study.see.trackfile",
    "classify": "study.answer", "Answer": "study.answer", "Runner": "study.runs.runner",
}
"""The public API: ``study.<name>`` -> the module that defines it (``module:attribute`` where the names differ)."""

__all__ = ["CLASSES", *EXPORTS]


def __getattr__(name: str) -> object:
    if name in EXPORTS:
        module, _, attr = EXPORTS[name].partition(":")
        value = getattr(importlib.import_module(module), attr or name)
    elif name in SHORT_NAMES:
        value = importlib.import_module(SHORT_NAMES[name])
    else:
        raise AttributeError(f"module 'study' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *EXPORTS, *SHORT_NAMES})
