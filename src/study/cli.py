"""The ``study`` command line: one subcommand per job, each a thin wrapper over the package.

Every error caused by the user's input is a :class:`study.errors.StudyError`; ``main`` prints it as
one line, ``study: error: ...``, and returns 2. Anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from study.errors import StudyError

Handler = Callable[[argparse.Namespace], int]


def _add_synth(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "synth",
        help="simulate a dataset of light and heavy trajectories with MuJoCo",
        description=(
            "Simulate the study's dataset: trajectories of a light (bouncy) and a heavy (sliding) "
            "object thrown onto the ground, train and test splits from disjoint seeds. The file is "
            "named by a hash of its config, seed and code version, written atomically, and reused "
            "when it already exists. Prints the path of the dataset."
        ),
    )
    p.add_argument(
        "--preset",
        choices=["smoke", "paper"],
        default="paper",
        help="dataset size: 'paper' = 1000 train + 1000 test trajectories per class, 10 s each; "
        "'smoke' = a few short trajectories, for tests (default: %(default)s)",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (default: %(default)s)")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        help="write the dataset to this file instead of data/synth-<hash>.npz",
    )
    p.add_argument("--data-dir", type=Path, default=Path("data"), help="cache folder (default: %(default)s)")
    p.add_argument("--threads", type=int, default=None, help="simulation threads (default: all cores)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    def run(a: argparse.Namespace) -> int:
        from study import synth

        cfg = synth.SynthConfig.preset(a.preset)
        path = synth.generate_to_file(
            cfg, seed=a.seed, out=a.out, data_dir=a.data_dir, threads=a.threads, progress=not a.no_progress
        )
        print(path)
        return 0

    p.set_defaults(run=run)


def _add_book(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "book",
        help="execute the chapters with papermill and build the HTML book",
        description=(
            "Execute each chapter listed in _toc.yml (jupytext MyST sources in book/) with papermill, "
            "injecting the preset into its 'parameters' cell, into executed copies under "
            "_build/executed/book/; then build the Jupyter Book from those copies into _build/html "
            "with execution off and every warning an error. A chapter re-executes only when its "
            "source, the preset, the study package, or a file or folder named by one of its string "
            "parameters changed. A failing cell stops the run with one line naming the chapter and "
            "cell; its partial copy is kept in _build/failed/. Per-chapter times are written to "
            "_build/executed/timings.json. Prints the path of index.html."
        ),
    )
    p.add_argument(
        "--preset",
        choices=["smoke", "paper"],
        default="paper",
        help="injected as the chapters' 'preset' parameter: 'paper' = the paper's scale; 'smoke' = "
        "tiny runs, for tests (default: %(default)s)",
    )
    p.add_argument("--force", action="store_true", help="re-execute every chapter even if its cached copy is current")
    p.add_argument(
        "--only",
        metavar="CHAPTER",
        action="append",
        default=None,
        help="re-execute this chapter (by file stem, e.g. 'data'), even if cached; repeatable. The other "
        "chapters keep their executed copies, even out-of-date ones, except that a chapter with no "
        "copy at all is executed; the whole book is still built",
    )
    p.add_argument(
        "--root",
        type=Path,
        default=Path("."),
        help="project root holding _config.yml, _toc.yml and book/; chapters run with it as their "
        "working folder (default: .)",
    )
    p.add_argument("--no-build", action="store_true", help="execute the chapters but skip the jupyter-book build")

    def run(a: argparse.Namespace) -> int:
        from study import book

        book.build(root=a.root, preset=a.preset, force=a.force, only=a.only, html=not a.no_build)
        return 0

    p.set_defaults(run=run)


COMMANDS: list[Callable[[argparse._SubParsersAction], None]] = [_add_synth, _add_book]


def build_parser() -> argparse.ArgumentParser:
    """The ``study`` argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="study",
        description=(
            "The motion-pattern study (arXiv:1609.00361, rebuilt with MuJoCo, PyTorch and OpenCV): "
            "simulate trajectories, build the book. Run 'study COMMAND --help' for each command."
        ),
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for add in COMMANDS:
        add(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``study`` console script; returns the exit status."""
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except StudyError as e:
        print(f"study: error: {' '.join(str(e).split())}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("study: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
