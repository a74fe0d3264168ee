"""The ``study`` command line: one subcommand per job, each a thin wrapper over the package.

Every error caused by the user's input is a :class:`study.core.errors.StudyError`; ``main`` prints it as
one line, ``study: error: ...``, and returns 2. Anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import NoReturn

from study.core import presets
from study.core.errors import ConfigError, StudyError, check_writable, removed_on_error
from study.core.fielddoc import field_docs
from study.see import paths


def _plain(doc: str) -> str:
    """A docstring as ``--help`` text: reST roles as plain words, ``%`` escaped for argparse; its literals are left
    for :func:`_name_flags`."""
    return re.sub(r":\w+:`~?([^`]*)`", r"\1", doc).replace("%", "%%")


def _name_flags(parser: argparse.ArgumentParser) -> None:
    """Rewrite the help of every option of ``parser`` in the command's own terms: a literal that names another of
    its options becomes that flag (``observe_noise`` -> --observe-noise), any other literal a quoted word."""
    flags = {s for a in parser._actions for s in a.option_strings}

    def word(m: re.Match) -> str:
        flag = "--" + m[1].replace("_", "-")
        return flag if flag in flags else f"'{m[1]}'"

    for action in parser._actions:
        if action.help:
            action.help = re.sub(r"``(.+?)``", word, action.help)


def _lower(text: str) -> str:
    """A choice as typed, in any case: the choices are lower case."""
    return text.lower()


class _Parser(argparse.ArgumentParser):
    """argparse with its errors on one line, as every other error of the command (no usage block before it)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}; see {self.prog} --help\n")


def _add_fields(p: argparse.ArgumentParser | argparse._ArgumentGroup, cls: type, names: Sequence[str], *,
                choices: dict[str, Sequence[str]] | None = None, more: dict[str, str] | None = None) -> None:
    """One option per field of the config dataclass ``cls``, its default, type, choices and help taken from the
    field itself (its docstring is the help, its ``Literal`` type the choices, its name the flag), so the command
    line cannot drift from the config."""
    from study.learn.config import choices as literal_choices  # no torch

    fields = {f.name: f for f in dataclasses.fields(cls)}
    docs = field_docs(cls)
    allowed = {**literal_choices(cls), **(choices or {})}
    for name in names:
        default = fields[name].default
        help_text = _plain(docs[name]) + (more or {}).get(name, "") + " (default: %(default)s)"
        extra = {"choices": allowed[name]} if name in allowed else {}
        kind = _lower if name in allowed and isinstance(default, str) else type(default)  # names: any case
        p.add_argument("--" + name.replace("_", "-"), dest=name, type=kind, default=default, help=help_text, **extra)


def _add_preset(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument("--preset", choices=presets.NAMES, default=presets.DEFAULT,
                   help=f"{what}: {presets.describe()} (default: %(default)s)")


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
    _add_preset(p, "dataset size")
    p.add_argument("--seed", type=int, default=0, help="random seed (default: %(default)s)")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        help="write the dataset to this file instead of data/synth-<hash>.npz",
    )
    p.add_argument("--data-dir", type=Path, default=None,
                   help="cache folder (default: $STUDY_DATA_DIR, else data/ here)")
    p.add_argument("--threads", type=int, default=None, help="simulation threads (default: all cores)")
    p.add_argument("--train-per-class", type=int, default=None, metavar="N",
                   help="training throws per class (default: the preset's)")
    p.add_argument("--test-per-class", type=int, default=None, metavar="N",
                   help="test throws per class (default: the preset's)")
    p.add_argument("--priors", type=Path, default=None, metavar="FILE",
                   help="a TOML or JSON file of the classes' (and the launch's) ranges, put over the preset's: "
                   "sections [light], [heavy], [launch], e.g. 'mass = [0.05, 0.3]' (see study.simulate.priors)")
    from study.simulate.synth import SynthConfig

    _add_fields(p, SynthConfig, ["engine"])
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    def run(a: argparse.Namespace) -> int:
        from study.simulate import synth

        cfg = synth.SynthConfig.preset(a.preset)
        if a.priors is not None:
            from study.simulate.priors import read_priors

            cfg = read_priors(a.priors, cfg)
        for flag, n in (("--train-per-class", a.train_per_class), ("--test-per-class", a.test_per_class)):
            if n is not None and n < 1:
                raise ConfigError(f"{flag} {n}: give at least 1 throw per class")
        sizes = {k: v for k, v in (("n_train", a.train_per_class), ("n_test", a.test_per_class)) if v is not None}
        if sizes:
            cfg = cfg.replace(**sizes)
        if a.engine != cfg.engine:  # Bullet has no air: its data set is the air-off one of the same throws
            cfg = cfg.replace(engine=a.engine, air=cfg.air and a.engine == "mujoco")
        with removed_on_error(a.out):
            if a.out is not None:
                check_writable(a.out, "dataset")
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
    _add_preset(p, "injected as the chapters' 'preset' parameter")
    p.add_argument("--force", action="store_true", help="re-execute every chapter even if its cached copy is current")
    p.add_argument(
        "--only",
        metavar="CHAPTER",
        action="append",
        default=None,
        help="re-execute this chapter (by file stem, e.g. 'data'), even if cached; repeatable. The other "
        "chapters keep their executed copies, even out-of-date ones; one never executed gets a page saying "
        "so (unless the chapter named is the summary, which reads them all); the whole book is still built",
    )
    p.add_argument(
        "--root",
        type=Path,
        default=Path("."),
        help="project root holding _config.yml, _toc.yml and book/; chapters run with it as their "
        "working folder (default: .)",
    )
    p.add_argument("--no-build", action="store_true", help="execute the chapters but skip the jupyter-book build")
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default="",
        help="train the chapters' runs on a Dask cluster instead of a local process pool: 'local' starts one "
        "LocalCluster for the build (on the loopback address, one single-threaded worker per core); an address "
        "(tls://host:8786) is a scheduler you started, reached with your Dask configuration's security settings. "
        "Every worker needs the study package installed and the data folder on a shared path; a scheduler must "
        "never listen on an open network (it runs whatever code reaches it). Not part of any cache key",
    )
    p.add_argument(
        "--device",
        default="cpu",
        help="where the runs train: 'cpu' (default), 'cuda' (a GPU: runs of one shape train as stacks of many, each "
        "as it would alone; their keys name the GPU, whose rounding may depend on the stack's size), or 'auto' "
        "(a GPU where there is one, said on the terminal)",
    )
    p.add_argument(
        "--data-dir",
        type=Path,
        default=None,
        help="cache folder of every data set, run, model and video the chapters make (default: $STUDY_DATA_DIR, "
        "else data/ under --root): keep it outside the work tree to resume a build from another checkout",
    )

    def run(a: argparse.Namespace) -> int:
        from study import book

        book.build(root=a.root, preset=a.preset, force=a.force, only=a.only, html=not a.no_build, scheduler=a.scheduler,
                   device=a.device, data_dir=a.data_dir)
        return 0

    p.set_defaults(run=run)


TRAIN_FIRST = ("dims", "inputs", "observe", "length", "seed")
"""``study train``'s options a user needs (what the model reads, what it is trained on, how long its input is, its
seed), shown first; the rest are the study's protocol."""


def _add_train(sub: argparse._SubParsersAction) -> None:
    from study.learn.config import TrainConfig  # no torch

    p = sub.add_parser(
        "train",
        help="train the paper's classifier on a dataset file and save it as a model directory",
        description=(
            "Train the light/heavy classifier (2 x 64 peephole LSTM, dropout, softmax on the last "
            "frame) on the train split of a dataset file, early-stopping on a seeded validation part "
            "of it; the test split is not touched. Deterministic for a given seed. Writes the model "
            "directory (weights, config, normalisation, history, data key) atomically. Every option "
            "below is a field of study.learn.config.TrainConfig, with its default: the study's protocol "
            "(Table 1's configuration on the paper preset). Prints JSON: the model, its best epoch, its "
            "validation accuracy with its 95 % Wilson interval and whether it failed to train (then a warning says "
            "what to change)."
        ),
    )
    first = p.add_argument_group("what to train (most users set only these)")
    first.add_argument("--data", type=Path, required=True, help="dataset file (.npz) written by `study synth`")
    first.add_argument("--out", type=Path, required=True, metavar="DIR",
                       help="model directory to write (replaced if it exists)")
    _add_fields(first, TrainConfig, TRAIN_FIRST)
    protocol = p.add_argument_group("the training protocol (the study's; change it to study the recipe)")
    _add_fields(protocol, TrainConfig, [f.name for f in dataclasses.fields(TrainConfig) if f.name not in TRAIN_FIRST])
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    def run(a: argparse.Namespace) -> int:
        import json

        import numpy as np

        from study.learn import train
        from study.simulate import synth

        fields = {f.name for f in dataclasses.fields(TrainConfig)}
        cfg = TrainConfig(**{k: v for k, v in vars(a).items() if k in fields})
        with removed_on_error(a.out):
            check_writable(a.out / "weights.pt", "model directory")
            ds = synth.load(a.data)
            tm = train.fit(ds, cfg, progress=not a.no_progress, warn=False)
            tm.save(a.out)
        if tm.failed:
            _warn(f"{a.out}: {tm.failure('cli')}")
            per_class = int(min(np.bincount(ds.train.y, minlength=2)))
            if per_class < ENOUGH_THROWS:
                _warn(f"{a.data} has {per_class} training throws a class; the protocol trains on the study's 3-second "
                      f"throws from about {ENOUGH_THROWS} a class (scripts/how_many_throws.py measures it): make more "
                      f"with `study synth --train-per-class {ENOUGH_THROWS} --out FILE`")
        print(json.dumps({"model": str(a.out), "best_epoch": tm.best_epoch, "val_accuracy": tm.val_accuracy,
                          "val_accuracy_interval": _interval(round(tm.val_accuracy * tm.n_val), tm.n_val),
                          "failed": tm.failed}))
        return 0

    p.set_defaults(run=run)


def _interval(right: int, n: int) -> dict[str, float | str] | None:
    """The 95 % Wilson interval of ``right`` of ``n`` as JSON fields (``Interval.to_dict``); None for n = 0 (a
    model saved before its validation size was recorded)."""
    from study.learn.metrics import wilson

    return wilson(right, n).to_dict() if n else None


ENOUGH_THROWS = 200
"""Training throws a class from which the protocol trained in every seed of ``scripts/how_many_throws.py`` (3-second
throws; at 50 and 100 a class one seed of three failed, at 25 or fewer every seed)."""


def _warn(message: str) -> None:
    """One warning line on the terminal, as errors are printed."""
    print(f"study: warning: {' '.join(message.split())}", file=sys.stderr)


def _add_tracker_options(p: argparse.ArgumentParser) -> None:
    """The colour tracker's options (fields of ``study.see.config.TrackConfig``), shared by track and classify."""
    from study.see.config import COLORS, TrackConfig  # no OpenCV

    g = p.add_mutually_exclusive_group()
    ranges = "; ".join(f"{name} H {lo[0]}-{hi[0]}, S {lo[1]}-{hi[1]}, V {lo[2]}-{hi[2]}" for name, (lo, hi) in COLORS.items())
    _add_fields(g, TrackConfig, ["color"], choices={"color": list(COLORS)},
                more={"color": f" (HSV ranges, OpenCV scale: {ranges})"})
    g.add_argument("--hsv", type=float, nargs=6, metavar=("H", "S", "V", "H", "S", "V"),
                   help="explicit HSV range, low then high, OpenCV scale (H 0-179, S and V 0-255); "
                   "a low H above the high H wraps through red")
    _add_fields(p, TrackConfig, ["max_gap", "min_found"])
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")


SCALE_FROM = paths.SCALE_FROM
"""How one scale can be read (``study.see.paths``, which imports no numerics)."""
SCALE_FROM_DEFAULT = paths.DEFAULT
"""How the command line reads the scale unless told."""


def _add_object_options(p: argparse.ArgumentParser, tennis_default: bool) -> None:
    """What was thrown, for the pixel -> metre scale (``study.see.scale``), shared by track and classify."""
    p.add_argument("--object-size", type=float, nargs="+", default=None, metavar="METRES",
                   help="the object's size in metres: a ball's diameter; a box's edge (a cube) or its three edges; a "
                   "cylinder's diameter and length" + (" (default: a tennis ball's 0.067 with --color tennis; for any "
                                                       "other colour, required)" if tennis_default else ""))
    p.add_argument("--object-shape", choices=("ball", "box", "cylinder"), default="ball",
                   help="what was thrown (default: %(default)s); the scale reads the silhouette this shape shows")
    p.add_argument("--scale-from", choices=SCALE_FROM, default=SCALE_FROM_DEFAULT,
                   help="metres per pixel from the object's size in pixels at rest at the end of the video ('rest'), "
                   "from its mean over the video ('mean': a tumbling box shows every side), or from gravity ('gravity': "
                   "the free flights' fall, 9.81 m/s^2; needs the object seen in the air) (default: %(default)s)")
    p.add_argument("--metres-per-pixel", type=float, default=None,
                   help="the image scale at the object's distance, if you measured it; overrides --object-size")
    p.add_argument("--floor", type=Path, default=None, metavar="FLOOR.csv",
                   help="four or more marks on the floor (five or more recommended): a CSV with the header u,v,x,y, "
                   "one row per mark, its pixel in the video (u right, v down, the top-left pixel's centre at 0,0) "
                   "and its position on the floor in metres; or, for marks of magenta paper, the header x,y and "
                   "their positions only (five or more, laid out with no symmetry): they are found in the video. "
                   "The camera they give places each frame's centre (its contacts on the floor, its flights between "
                   "them, the blob's size against --object-size) instead of one scale for the whole video; with "
                   "--manifest, for every clip of the folder (a camera that stood still). Experimental: on rendered "
                   "video its heights are not yet as close as on clean pixels (scripts/floor_sweep.py measures them)")


def _object_shape(a: argparse.Namespace):
    """The ``ObjectShape`` the object options ask for, or None without --object-size."""
    from study.answer import shape

    return shape(tuple(a.object_size), a.object_shape) if a.object_size else None


def _on_floor(a: argparse.Namespace):
    """``study track --floor``: the video tracked, with heights through the camera the floor marks give; prints what
    the floor says of the camera. The floor is read (and its marks found) before the tracking."""
    from study.core.errors import ConfigError
    from study.see import track
    from study.see.floor import contact_height, on_floor
    from study.answer import checked_floor
    from study.see.marks import read

    marks = read(a.floor)
    shape = _object_shape(a)
    if shape is None:
        raise ConfigError("--floor: give the object's size (--object-size, and --object-shape) for the height of its "
                          "centre when it lies on the floor")
    found = checked_floor(marks, a.video)  # before the tracking
    traj, cal = on_floor(track.track_video(a.video, _track_config(a)), found, shape.rest_height(),
                         shape.mean_size(), contact_height(shape))
    print(f"{a.video}: {cal.note()}")
    return traj


def _track_config(a: argparse.Namespace):
    """The ``TrackConfig`` the tracker options of :func:`_add_tracker_options` ask for."""
    from study.see.config import TrackConfig

    return TrackConfig(color=a.color, hsv=tuple(a.hsv) if a.hsv else None, max_gap=a.max_gap,
                       min_found=a.min_found, progress=not a.no_progress)


def _add_track(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "track",
        help="track a coloured object through a video and write its trajectory",
        description=(
            "Follow an object of one colour through VIDEO (streamed frame by frame): an HSV mask, "
            "the most plausible blob per frame, gaps of up to --max-gap frames filled by linear "
            "interpolation, longer gaps splitting the trajectory. Prints one line: frames found, "
            "filled and missing, and the pieces. Heights are in pixels above the lowest position "
            "unless --object-size or --metres-per-pixel gives a scale."
        ),
    )
    p.add_argument("video", type=Path, help="the video file (.mp4, .avi, ... anything OpenCV decodes)")
    _add_tracker_options(p)
    p.add_argument("--out", type=Path, default=None,
                   help="write the trajectory CSV here (frame, t_s, u_px, v_px, height, status, segment, confidence)")
    p.add_argument("--overlay", type=Path, default=None, help="write a copy of the video with the track drawn (.mp4)")
    _add_object_options(p, tennis_default=False)
    p.add_argument("--ground-v", type=float, default=None, help="image row of the object's centre on the ground (default: its lowest position)")

    def run(a: argparse.Namespace) -> int:
        from study.see import track

        with removed_on_error(a.out, a.overlay):
            for path, what in ((a.out, "trajectory CSV"), (a.overlay, "overlay video")):
                if path is not None:
                    check_writable(path, what)  # before the tracking, not after it
            if a.floor is not None:
                traj = _on_floor(a)
            else:
                traj = track.track_video(a.video, _track_config(a), ground_v=a.ground_v, shape=_object_shape(a),
                                         scale_from=a.scale_from, metres_per_pixel=a.metres_per_pixel)
            if a.out:
                track.write_csv(traj, a.out)
            if a.overlay:
                track.write_overlay(traj, a.overlay, progress=not a.no_progress)
        pieces = ", ".join(f"{s.t[0]:.2f}-{s.t[-1]:.2f} s" for s in traj.segments())
        print(f"{a.video}: found in {int(traj.measured.sum())} of {len(traj.t)} frames, "
              f"{int(traj.filled.sum())} filled, {len(traj.segments())} piece(s): {pieces}")
        return 0

    p.set_defaults(run=run)


def _add_evaluate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "evaluate",
        help="score a trained model on a dataset's test split; prints JSON",
        description=(
            "Load a model directory written by `study train` and score it on the test split of a "
            "dataset file. Prints JSON: accuracy with its 95 % Wilson interval over the test throws "
            "(accuracy_interval), per-class accuracy, the confusion matrix (rows: true class, columns: "
            "predicted; classes in the order given), and the data keys."
        ),
    )
    p.add_argument("--model", type=Path, required=True, metavar="DIR", help="model directory written by `study train`")
    p.add_argument("--data", type=Path, required=True, help="dataset file (.npz) written by `study synth`")

    def run(a: argparse.Namespace) -> int:
        import json

        from study.learn import train
        from study.simulate import synth

        tm = train.load(a.model)
        ds = synth.load(a.data)
        res = train.evaluate(tm, ds.test)
        right = sum(row[k] for k, row in enumerate(res["confusion"]))  # the diagonal
        res.update(accuracy_interval=_interval(right, res["n"]), model=str(a.model), data=str(a.data),
                   data_key=ds.key, trained_on=tm.data_key)
        print(json.dumps(res, indent=1))
        return 0

    p.set_defaults(run=run)


def _measured_words() -> str:
    """What the shipped copy of a paper build's camera sweep measured, for ``classify --help``."""
    from study.runs.measured import read_shipped
    from study.see.paths import DEFAULT

    shipped = read_shipped()
    if shipped is None:
        return "This copy of the package ships no such measurement; a book build makes one. "
    floor = shipped.span("floor")
    return (f"On {shipped.source()}, the models the study compared labelled {shipped.span(DEFAULT)} of the throws "
            f"right through one scale, {floor or 'an unmeasured share'} through floor marks (--floor, experimental), "
            f"and {shipped.span('exact')} from their exact heights. ")


def _add_render(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "render",
        help="render sample videos of a throw of each class, to try 'study track' and 'study classify' on",
        description=(
            "Render throws of each class (light and heavy, drawn from the study's priors, a 0.2 m orange box) "
            "into OUT as a phone would film them (640 x 360, 60 frames a second, 3 s): the videos, a "
            "MANIFEST.csv (file, label, color, object_size, object_shape) for 'study classify --manifest', "
            "six magenta floor marks in view, with a FLOOR.csv of their positions and pixels (as exact clicks) "
            "and a MARKS.csv of their positions only (found in the video) for '--floor'; beside each video its "
            "ground truth (.csv). About half a minute a "
            "video. Prints the videos and the commands to try on them."
        ),
    )
    p.add_argument("out", type=Path, metavar="OUT", help="the folder to write the samples into (made if missing)")
    p.add_argument("--per-class", type=int, default=1, metavar="N", help="throws of each class (1-20; default 1)")
    p.add_argument("--seed", type=int, default=None,
                   help="seed of the throws (default: one no split of the book's trains or tests on)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")

    def run(a: argparse.Namespace) -> int:
        from study.core.errors import ConfigError
        from study.methods import sample

        if not 1 <= a.per_class <= 20:
            raise ConfigError(f"--per-class {a.per_class}: give a whole number of throws a class from 1 to 20")
        videos = sample.write(a.out, a.per_class, sample.SEED if a.seed is None else a.seed,
                              progress=not a.no_progress)
        first = videos[0]
        print("\n".join(str(v) for v in videos))
        print(f"try: study classify {first} --color {sample.COLOR} --object-size 0.2 --object-shape box "
              f"--floor {a.out / 'FLOOR.csv'}\n"
              f"     study classify {first} --color {sample.COLOR} --object-size 0.2 --object-shape box "
              f"--floor {a.out / 'MARKS.csv'}\n"
              f"     study classify {first} --color {sample.COLOR} --object-size 0.2 --object-shape box\n"
              f"     study classify --manifest {a.out / 'MANIFEST.csv'}")
        return 0

    p.set_defaults(run=run)


def _add_classify(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "classify",
        help="say whether a tracked object is light (bouncy) or heavy (sliding)",
        description=(
            "Say whether a thrown object is light (bounces: safe to pass) or heavy (slides: must avoid) "
            "from a video of it, with no camera calibration: the object's colour and size are enough to answer, "
            "though not to answer well: one scale per clip leaves the heights far off, and each answer quotes the "
            f"accuracy the study measured for its path. {_measured_words()}"
            "VIDEO_OR_CSV is a video (tracked as 'study track' does, its heights in metres from the object's "
            "mean apparent size) or a trajectory CSV from 'study track --out'; --manifest FILE does every "
            "video of a folder. The model: --model DIR (from 'study train'), else the one the last book "
            "build in the data folder recommends. The longest piece of the track is resampled to the "
            "model's frame rate and cut or zero-padded to its input length. Prints the class and p(heavy); how "
            "far to trust it (the accuracy the study's camera sweep measured for such a model through this path, "
            "with its 95 % interval, from the data folder's build or the copy shipped with the package); "
            "'cannot tell' where p(heavy) falls inside the recommended model's cannot-tell band (certified on "
            "throws no training saw; counted neither right nor wrong); and what it assumed (the scale, the "
            "ground, the frames read)."
        ),
    )
    p.add_argument("input", type=Path, metavar="VIDEO_OR_CSV", nargs="?",
                   help="a video, or a trajectory CSV from 'study track --out'")
    p.add_argument("--manifest", type=Path, default=None, metavar="FILE",
                   help="classify every video a MANIFEST.csv lists instead (columns file, label if known, and "
                   "optionally color (a name or six HSV numbers), object_size (metres), object_shape; rows without "
                   "them use --color and --object-size); prints one line a video and how many were right")
    p.add_argument("--out", type=Path, default=None, metavar="CSV",
                   help="with --manifest: write each video's answer here too (file, true, label, p, p_heavy, "
                   "correct, trust, assumed, warnings, error)")
    p.add_argument("--model", type=Path, default=None,
                   help="trained model directory (default: the model the last book build in the data folder "
                   "recommends for a camera, its seeds' mean)")
    p.add_argument("--data-dir", type=Path, default=None,
                   help="data folder whose recommended model to use without --model (default: $STUDY_DATA_DIR, "
                   "else data/ here)")
    _add_tracker_options(p)
    _add_object_options(p, tennis_default=True)
    p.add_argument("--rest-height", type=float, default=None,
                   help="height of the object's centre at rest, metres (default: from --object-size and --object-shape)")

    def run(a: argparse.Namespace) -> int:
        from study import answer
        from study.core.errors import ConfigError

        if (a.input is None) == (a.manifest is None):
            raise ConfigError("give a video or CSV to classify, or --manifest FILE for a folder of them "
                              "(one of the two)")
        if a.manifest is not None:
            return _classify_manifest(a)
        if a.out is not None:
            raise ConfigError("--out writes a manifest's answers; with one video, its answer is printed")
        shape = _object_shape(a) or answer.BY_COLOUR  # a tennis ball, for the tennis colour only
        ans = answer.classify(a.input, a.model, track_config=_track_config(a), object_shape=shape,
                              scale_from=a.scale_from, metres_per_pixel=a.metres_per_pixel,
                              rest_height=a.rest_height, data_dir=a.data_dir, floor=a.floor)
        for w in ans.warnings:
            _warn(w)
        print(ans.text(warnings=False))
        return 0

    p.set_defaults(run=run)


def _classify_manifest(a: argparse.Namespace) -> int:
    """``study classify --manifest``: every video of the manifest, one line each, then the tally."""
    from study import answer

    if a.out is not None:
        check_writable(a.out, "answers CSV")  # before the tracking, not after it
    rows = answer.classify_manifest(a.manifest, a.model, color=a.color,
                                    object_size=a.object_size[0] if a.object_size else None,
                                    scale_from=a.scale_from, data_dir=a.data_dir, what="--manifest", floor=a.floor)
    for w in next((r.answer.warnings for r in rows if r.answer), ()):  # one model answered them all
        _warn(w)
    from study.trust import p_text

    for r in rows:
        got = (f"{r.answer.label} (p(heavy) = {p_text(r.answer.p_heavy)})" if r.answer else f"not classified: {r.error}")
        mark = {True: "  right", False: "  wrong", None: ""}[r.correct]
        print(f"{r.file}: {got}" + (f"; true {r.true}{mark}" if r.true else ""))
    known = [r.correct for r in rows if r.correct is not None]
    unsure = sum(r.answer is not None and r.answer.label == answer.CANNOT_TELL for r in rows)
    first = next((r.answer for r in rows if r.answer), None)
    print(f"{len(rows)} videos, {sum(r.answer is not None for r in rows)} classified"
          + (f", {sum(known)} of {len(known)} labelled ones right" if known else "")
          + (f", {unsure} cannot tell (counted neither right nor wrong)" if unsure else "")
          + (f"; answered by {first.model}" if first else ""))
    if first is not None and first.trust is not None:
        print(f"trust: {first.trust}")
    if a.out is not None:
        print(f"answers written to {answer.write_answers(rows, a.out)}")
    return 0


def _add_results(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "results",
        help="list a build's numbers with their intervals, or compare two builds",
        description=(
            "Read a results file written by `study book` (_build/results.json: every number of the book "
            "with its 95 % interval, the paper's number and the verdict) and print it. With --compare, "
            "pair its numbers with another build's and list those that moved: one build's value outside "
            "the other's interval, and the verdicts the two decide differently. Exit status 0 either way (2 for a "
            "missing or malformed file)."
        ),
    )
    p.add_argument("file", type=Path, nargs="?", default=Path("_build/results.json"),
                   help="results file (default: %(default)s)")
    p.add_argument("--compare", type=Path, metavar="OTHER", default=None, help="another build's results file")
    p.add_argument("--all", action="store_true", help="with --compare, list every shared number, not only those that moved")

    def run(a: argparse.Namespace) -> int:
        from study.book import results
        from study.report.reported import Verdict
        from study.report.text import fmt, fmt_value

        mine = results.load(a.file)
        if a.compare is None:
            for name, n in mine.items():
                if isinstance(n, Verdict):
                    print(f"{name}: {n.verdict}")
                    continue
                paper = "" if n.paper is None else f"  paper {fmt_value(n.paper, n.unit)}"
                verdict = f"  {n.verdict}" if n.verdict else ""
                print(f"{name}: {fmt(n)}{paper}{verdict}")
            return 0
        other = results.load(a.compare)
        c = results.compare(mine, other)
        for m in c.pairs if a.all else c.moved:
            flag = "MOVED" if m.moved else "same "
            print(f"{flag} {m.name}: {fmt(m.a)}  vs  {fmt(m.b)}")
        for name, va, vb in c.verdicts:
            print(f"VERDICT {name}: {va}  vs  {vb}")
        print(f"{len(c.moved)} of {len(c.pairs)} shared numbers moved outside the other build's interval; "
              f"{len(c.verdicts)} verdicts differ; {len(c.only_a)} only in {a.file}, {len(c.only_b)} only in "
              f"{a.compare}")
        return 0

    p.set_defaults(run=run)


COMMANDS: list[Callable[[argparse._SubParsersAction], None]] = [
    _add_synth, _add_book, _add_train, _add_evaluate, _add_render, _add_track, _add_classify, _add_results,
]


def build_parser() -> argparse.ArgumentParser:
    """The ``study`` argument parser with every subcommand."""
    parser = _Parser(
        prog="study",
        description=(
            "The motion-pattern study (arXiv:1609.00361, rebuilt with MuJoCo, PyTorch and OpenCV): "
            "simulate trajectories, train and evaluate, build the book -- and your own video: 'study track VIDEO' "
            "follows a coloured object through it, 'study classify VIDEO --color C --object-size D' says light or "
            "heavy (and how far to trust it), 'study render OUT' makes sample clips to try them on. Run 'study "
            "COMMAND --help' for each command."
        ),
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=_Parser)
    for add in COMMANDS:
        add(sub)
    for command in sub.choices.values():
        _name_flags(command)
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
    except BrokenPipeError:  # `study results | head`: the reader has gone, nothing more to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # so the exit's flush cannot fail again
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
