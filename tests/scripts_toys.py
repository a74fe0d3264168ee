"""The project's scripts and benchmarks, loaded as modules for their tests (they are files, not package modules)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

REPO = Path(__file__).resolve().parents[1]


def script(path: str) -> ModuleType:
    """The file ``path`` (relative to the repository, e.g. ``"scripts/build_time.py"``) run as a module named for its
    stem, registered in ``sys.modules`` (a dataclass in it looks its module up there)."""
    spec = importlib.util.spec_from_file_location(Path(path).stem, REPO / path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module
