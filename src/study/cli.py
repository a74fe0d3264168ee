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
            "Execute each chapter of book/ (jupytext MyST sources) with papermill, injecting the "
            "preset, into executed copies under _build/executed, then build the Jupyter Book to "
            "_build/html with execution off, failing on warnings. A chapter re-executes only when "
            "its source, its parameters, the study package or its inputs changed."
        ),
    )
    p.add_argument("--preset", choices=["smoke", "paper"], default="paper", help="chapter preset (default: %(default)s)")
    p.add_argument("--force", action="store_true", help="re-execute every chapter even if its cached copy is current")
    p.add_argument("--only", metavar="CHAPTER", action="append", default=None,
                   help="execute only this chapter (by file stem, e.g. 'data'); repeatable; the book is still built")
    p.add_argument("--root", type=Path, default=Path("."), help="project root holding _config.yml, _toc.yml, book/ (default: .)")
    p.add_argument("--no-build", action="store_true", help="execute chapters but skip jupyter-book build")

    def run(a: argparse.Namespace) -> int:
        from study import book

        book.build(root=a.root, preset=a.preset, force=a.force, only=a.only, html=not a.no_build)
        return 0

    p.set_defaults(run=run)


# study.train.TrainConfig's defaults, repeated so that `study --help` need not import torch (2-3 s);
# tests/test_train.py checks that the two agree.
_TRAIN_DEFAULTS = argparse.Namespace(seed=0, cell="peephole", max_epochs=40, lr=3e-3, batch_size=32,
                                     truncation=30, dropout=0.2, patience=8)


def _add_train(sub: argparse._SubParsersAction) -> None:
    d = _TRAIN_DEFAULTS
    p = sub.add_parser(
        "train",
        help="train the paper's classifier on a dataset file and save it as a model directory",
        description=(
            "Train the light/heavy classifier (2 x 64 peephole LSTM, dropout, softmax on the last "
            "frame) on the train split of a dataset file, early-stopping on a seeded validation part "
            "of it; the test split is not touched. Deterministic for a given seed. Writes the model "
            "directory (weights, config, normalisation, history, data key) atomically."
        ),
    )
    p.add_argument("--data", type=Path, required=True, help="dataset file (.npz) written by `study synth`")
    p.add_argument("--dims", choices=["xyz", "z"], required=True, help="input coordinates: all three, or the height only")
    p.add_argument("--length", type=float, required=True, metavar="SECONDS",
                   help="input length: the first SECONDS of every trajectory (must not exceed the data)")
    p.add_argument("--seed", type=int, default=d.seed, help="seed of the split, weights, batches, dropout (default: %(default)s)")
    p.add_argument("--cell", choices=["peephole", "lstm", "gru"], default=d.cell,
                   help="recurrent cell: the paper's peephole LSTM, nn.LSTM or nn.GRU (default: %(default)s)")
    p.add_argument("--epochs", type=int, default=d.max_epochs, help="most epochs; early stopping may end sooner (default: %(default)s)")
    p.add_argument("--lr", type=float, default=d.lr, help="Adam learning rate (default: %(default)s)")
    p.add_argument("--batch-size", type=int, default=d.batch_size, help="trajectories per step (default: %(default)s)")
    p.add_argument("--truncation", type=int, default=d.truncation, metavar="FRAMES",
                   help="truncated BPTT: the loss back-propagates through at most this many last frames (default: %(default)s)")
    p.add_argument("--dropout", type=float, default=d.dropout,
                   help="probability of dropping a unit before the softmax; 0.2 = the paper's keep-probability 0.8 (default: %(default)s)")
    p.add_argument("--patience", type=int, default=d.patience, help="early-stopping patience in epochs (default: %(default)s)")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="model directory to write (replaced if it exists)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    def run(a: argparse.Namespace) -> int:
        import json

        from study import data, train

        ds = data.load(a.data)
        cfg = train.TrainConfig(dims=a.dims, length=a.length, seed=a.seed, cell=a.cell, max_epochs=a.epochs, lr=a.lr,
                          batch_size=a.batch_size, truncation=a.truncation, dropout=a.dropout, patience=a.patience)
        tm = train.fit(ds, cfg, progress=not a.no_progress)
        tm.save(a.out)
        print(json.dumps({"model": str(a.out), "best_epoch": tm.best_epoch, "val_accuracy": tm.val_accuracy}))
        return 0

    p.set_defaults(run=run)


def _add_evaluate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "evaluate",
        help="score a trained model on a dataset's test split; prints JSON",
        description=(
            "Load a model directory written by `study train` and score it on the test split of a "
            "dataset file. Prints JSON: accuracy, per-class accuracy, the confusion matrix (rows: "
            "true class, columns: predicted; classes in the order given), and the data keys."
        ),
    )
    p.add_argument("--model", type=Path, required=True, metavar="DIR", help="model directory written by `study train`")
    p.add_argument("--data", type=Path, required=True, help="dataset file (.npz) written by `study synth`")

    def run(a: argparse.Namespace) -> int:
        import json

        from study import data, train

        tm = train.load(a.model)
        ds = data.load(a.data)
        res = train.evaluate(tm, ds.test)
        res.update(model=str(a.model), data=str(a.data), data_key=ds.key, trained_on=tm.data_key)
        print(json.dumps(res, indent=1))
        return 0

    p.set_defaults(run=run)


COMMANDS: list[Callable[[argparse._SubParsersAction], None]] = [_add_synth, _add_book, _add_train, _add_evaluate]


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
