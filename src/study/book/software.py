"""The introduction's software table: the versions the book was executed with, read from the running kernel."""

from __future__ import annotations

import platform
from dataclasses import dataclass

import cv2
import matplotlib
import mujoco
import numpy
import torch

import study
from study.core.cache import source_hash
from study.learn import native
from study.report.reported import Reported
from study.report.text import Table


@dataclass(frozen=True)
class Numbers(Reported):
    """The introduction reports no number."""

    CHAPTER = "intro"


@dataclass(frozen=True)
class Software:
    """What the introduction shows of the copy being read."""

    numbers: Numbers
    versions: Table
    """Each package and its version."""
    preset: str
    """The preset the book was built with."""


def compute(preset: str) -> Software:
    """The versions of the packages the study runs on, and of the peephole LSTM's time loop."""
    versions = {
        "Python": platform.python_version(),
        "NumPy": numpy.__version__,
        "MuJoCo": mujoco.__version__,
        "PyTorch": torch.__version__,
        "OpenCV": cv2.__version__,
        "Matplotlib": matplotlib.__version__,
        "study": f"{study.__version__} (source {source_hash(words=True)})",
        "peephole LSTM time loop": "compiled (peephole.cpp, g++)" if native.backend() == "native"
        else "PyTorch operations (no C++ compiler)",
    }
    rows = [{"name": k, "version": f"`{v}`"} for k, v in versions.items()]
    return Software(Numbers(), Table(rows, {"name": "Package", "version": "Version"}), preset)
