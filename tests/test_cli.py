"""The command line as a user meets it: every command that writes answers a destination it cannot write
with one line naming the path, exits 2 and leaves nothing behind; `--help` costs no torch."""

from __future__ import annotations

import argparse
import dataclasses
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from study import cli
from study.core.errors import ModelError
from study.see import render

# CI runs as root, where a read-only folder is still writable: these paths cannot exist at all.
UNDER_PROC = "/proc/study-cannot-write-here"


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("study: error: "), err
    return lines[0]


@pytest.fixture(scope="module")
def dataset_file(smoke_dataset) -> Path:
    return smoke_dataset.path


@pytest.fixture(scope="module")
def small_video(tmp_path_factory) -> Path:
    cfg = render.RenderConfig(width=96, height=72, duration=0.5, shadows=False)
    qpos, qvel = render.initial_state((-0.5, 0.0, 0.8), (1.0, 0.0, 0.0))
    return render.render(render.class_model("light"), qpos, qvel, tmp_path_factory.mktemp("v") / "v.mp4", cfg).video


def bad_destinations(tmp_path: Path) -> list[tuple[Path, str]]:
    """(path, what the message must name) for a path under /proc and one under a regular file."""
    afile = tmp_path / "a-file.txt"
    afile.write_text("not a folder\n")
    return [(Path(UNDER_PROC) / "out", "/proc"), (afile / "out", "a-file.txt is a file, not a folder")]


def test_synth_out(tmp_path, capsys):
    for dest, why in bad_destinations(tmp_path):
        rc = cli.main(["synth", "--preset", "smoke", "--out", str(dest / "x.npz"), "--no-progress"])
        line = one_error_line(capsys)
        assert rc == 2 and str(dest / "x.npz") in line and why in line and "choose a folder" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file.txt"]


def test_train_out(tmp_path, dataset_file, capsys):
    for dest, why in bad_destinations(tmp_path):
        rc = cli.main(["train", "--data", str(dataset_file), "--dims", "z", "--length", "0.3", "--epochs", "1",
                       "--out", str(dest / "model"), "--no-progress"])
        line = one_error_line(capsys)
        assert rc == 2 and str(dest / "model") in line and why in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file.txt"]


@pytest.mark.slow  # renders a short video
@pytest.mark.parametrize("option, name", [("--out", "x.csv"), ("--overlay", "x.mp4")])
def test_track_out_and_overlay(tmp_path, small_video, capsys, option, name):
    for dest, why in bad_destinations(tmp_path):
        rc = cli.main(["track", str(small_video), "--color", "orange", option, str(dest / name), "--no-progress"])
        line = one_error_line(capsys)
        assert rc == 2 and str(dest / name) in line and why in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file.txt"]


def test_train_leaves_nothing_behind_on_bad_data(tmp_path, dataset_file, capsys):
    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(dataset_file.read_bytes()[: dataset_file.stat().st_size // 2])
    cases = [(tmp_path / "missing.npz", "no such file", "0.3"), (truncated, "cannot be read", "0.3"),
             (dataset_file, "needs 150", "5")]
    for data_file, why, length in cases:
        out = tmp_path / "new" / "folders" / "model"
        rc = cli.main(["train", "--data", str(data_file), "--length", length, "--out", str(out), "--no-progress"])
        line = one_error_line(capsys)
        assert rc == 2 and why in line, line
        assert not (tmp_path / "new").exists(), f"{why}: the folders made for the output are removed"


@pytest.mark.slow  # trains a tiny model
def test_a_failed_model_is_reported_by_train_and_classify(tmp_path, dataset_file, capsys):
    out = tmp_path / "m"
    rc = cli.main(["train", "--data", str(dataset_file), "--length", "0.5", "--epochs", "1", "--out", str(out),
                   "--no-progress"])
    captured = capsys.readouterr()
    assert rc == 0 and json.loads(captured.out)["failed"] is True
    warning = [ln for ln in captured.err.splitlines() if ln.startswith("study: warning: ")]
    assert len(warning) == 2 and "failed to train" in warning[0] and "--seed" in warning[0]
    assert "training throws a class" in warning[1] and "--train-per-class 200" in warning[1], "how many it needs"
    assert json.loads((out / "meta.json").read_text())["failed"] is True
    csv = tmp_path / "t.csv"
    csv.write_text("frame,t_s,u_px,v_px,height_m,status,segment,confidence\n"
                   + "".join(f"{i},{i / 30:.6f},10,{50 + i},{0.5 - i / 100:.4f},measured,0,1\n" for i in range(20)))
    assert cli.main(["classify", str(csv), "--model", str(out)]) == 0
    captured = capsys.readouterr()
    assert "study: warning: " in captured.err and "1 of 1 seed(s) failed to train" in captured.err
    assert "--lr" not in captured.err and "--epochs" not in captured.err, "classify names what classify accepts"
    assert "trained on exact trajectories" in captured.err and "--observe any-camera" in captured.err
    assert captured.out.startswith(f"{csv}: ") and "\n  trust: " in captured.out


def test_book_output_folder(tmp_path, capsys):
    (tmp_path / "_toc.yml").write_text("format: jb-book\nroot: book/notes\n")
    (tmp_path / "book").mkdir()
    (tmp_path / "book" / "notes.md").write_text("# Notes\n")
    (tmp_path / "_build").write_text("a file where the book's output folder should be\n")
    rc = cli.main(["book", "--root", str(tmp_path), "--preset", "smoke", "--no-build"])
    line = one_error_line(capsys)
    assert rc == 2 and "book output folder" in line and "_build is a file, not a folder" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["_build", "_toc.yml", "book"]


def test_help_does_not_import_torch():
    code = "import sys; from study import cli; cli.build_parser().format_help(); print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_the_scale_readings_offered_are_the_package_s():
    from study.see import scale

    assert cli.SCALE_FROM == scale.SCALE_FROM and cli.SCALE_FROM_DEFAULT == scale.DEFAULT in scale.SCALE_FROM


@pytest.mark.slow  # trains a tiny model and tracks a rendered video
def test_a_velocity_model_classifies_a_csv_and_a_video(tmp_path, dataset_file, small_video, capsys, monkeypatch):
    out = tmp_path / "v"
    assert cli.main(["train", "--data", str(dataset_file), "--length", "0.5", "--epochs", "1", "--inputs", "velocity",
                     "--out", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    assert json.loads((out / "config.json").read_text())["inputs"] == "velocity"
    assert cli.main(["track", str(small_video), "--color", "orange", "--object-size", "0.2", "--object-shape", "box", "--out",
                     str(tmp_path / "t.csv"), "--no-progress"]) == 0
    for source in (tmp_path / "t.csv", small_video):
        assert cli.main(["classify", str(source), "--model", str(out), "--color", "orange", "--object-size", "0.2",
                         "--object-shape", "box", "--scale-from", "mean", "--no-progress"]) == 0
        line, trust, note = capsys.readouterr().out.strip().splitlines()[-3:]
        assert line.startswith(f"{source}: ") and ("light (p(heavy) = " in line or "heavy (p(heavy) = " in line), line
        assert trust.startswith("  trust: ") and "mean silhouette path" in trust, trust
        assert note.startswith("  assumed: ") and "mm/px" in note and "frames found" in note, note
    # a track in pixels (no --object-size) is classified with the object's size given then, as the video is
    assert cli.main(["track", str(small_video), "--color", "orange", "--out", str(tmp_path / "px.csv"),
                     "--no-progress"]) == 0
    capsys.readouterr()
    flags = ["--model", str(out), "--object-size", "0.2", "--object-shape", "box", "--no-progress"]
    labels = []
    for source in (tmp_path / "px.csv", small_video):
        assert cli.main(["classify", str(source), "--color", "orange", *flags]) == 0
        line, _, note = capsys.readouterr().out.strip().splitlines()[-3:]
        labels.append(line.split(": ")[1].split(" (")[0])
        assert "RMS over" in note, note
    assert labels[0] == labels[1], "the pixel CSV and its video get the same answer"
    assert cli.main(["classify", str(tmp_path / "px.csv"), "--model", str(out), "--no-progress"]) == 0
    note = capsys.readouterr().out.strip().splitlines()[-1]
    assert "0.067 m over a" in note, "without --object-size, the object is a tennis ball, as for a video"
    # the user's path reads the video and the flags only: no render truth, no manifest, no camera beside it
    alone = tmp_path / "alone" / "clip.mp4"
    alone.parent.mkdir()
    shutil.copy(small_video, alone)
    from study.methods import videos
    from study.see import camera

    def no(*a, **k):
        raise AssertionError("the user's path read something other than the video and its flags")

    for where, name in ((render, "read_truth"), (videos, "read_manifest"), (camera.Camera, "heights")):
        monkeypatch.setattr(where, name, no)
    assert cli.main(["classify", str(alone), "--model", str(out), "--color", "orange", "--object-size", "0.2",
                     "--object-shape", "box", "--no-progress"]) == 0
    assert capsys.readouterr().out.startswith(f"{alone}: ")


def test_classify_without_a_model_and_without_a_build_says_how_to_get_one(tmp_path, capsys):
    csv = tmp_path / "t.csv"
    csv.write_text("frame,t_s,u_px,v_px,height_m,status,segment,confidence\n0,0,1,2,0.1,measured,0,1\n")
    rc = cli.main(["classify", str(csv), "--data-dir", str(tmp_path / "empty")])
    line = one_error_line(capsys)
    assert rc == 2 and "no recommended model" in line and "make book" in line and "--model DIR" in line
    assert "--observe any-camera" in line and "$STUDY_DATA_DIR" in line  # a model fit for video, and where data is
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "recommended.json").write_text("{not json")
    rc = cli.main(["classify", str(csv), "--data-dir", str(tmp_path / "d")])
    line = one_error_line(capsys)
    assert rc == 2 and "recommended.json cannot be read" in line


@pytest.mark.slow  # trains a tiny model
def test_classify_without_a_model_uses_the_builds_recommended_one(tmp_path, dataset_file, capsys):
    from study.learn.metrics import Interval
    from study.runs import recommended

    data = tmp_path / "data"
    out = data / "models" / "m"
    assert cli.main(["train", "--data", str(dataset_file), "--length", "0.5", "--epochs", "1", "--dims", "z",
                     "--out", str(out), "--no-progress"]) == 0
    recommended.save_one(data, "positions, exact", [out, out], Interval(0.9, 0.8, 0.95, "test"), "smoke")
    assert "models/m" in (data / "recommended.json").read_text()  # relative: the folder can move
    moved = tmp_path / "moved"
    data.rename(moved)
    csv = tmp_path / "t.csv"
    csv.write_text("frame,t_s,u_px,v_px,height_m,status,segment,confidence\n"
                   + "".join(f"{i},{i / 30:.6f},10,{50 + i},{0.5 - i / 100:.4f},measured,0,1\n" for i in range(20)))
    capsys.readouterr()
    assert cli.main(["classify", str(csv), "--data-dir", str(moved)]) == 0
    line = capsys.readouterr().out.strip()
    assert "smoke build's recommended model (positions, exact, 2 seeds; 90.0 %" in line, line
    iv = Interval(0.642, 0.529, 0.75, "test")
    one = recommended.PathModel("positions, exact", (moved / "models" / "m",), iv, {"mean": iv}, (0.0, 1.0))
    recommended.save(moved, "smoke", {recommended.ONE_SCALE: one}, measured={"positions-exact": {"mean": iv}})
    assert cli.main(["classify", str(csv), "--data-dir", str(moved)]) == 0
    said = capsys.readouterr()
    assert said.out.startswith(f"{csv}: cannot tell (p(heavy) = "), said.out
    assert "trust: 64.2 % [52.9, 75.0] right (the camera sweep of the smoke build" in said.out
    assert "cannot tell for p(heavy) 0.000-1.000" in said.out
    assert "trained on exact trajectories" in said.err and "64.2 % [52.9, 75.0]" in said.err, said.err
    import shutil

    shutil.rmtree(moved / "models")
    assert cli.main(["classify", str(csv), "--data-dir", str(moved)]) == 2
    assert "which is gone" in one_error_line(capsys)


@pytest.mark.parametrize("args, why", [(["--object-shape", "box", "--object-size", "0.1", "0.2"], "a box takes 1 or 3"),
                                       (["--object-size", "-0.2"], "sphere size (metres)")])
def test_a_shape_that_does_not_fit_its_sizes_is_one_line_and_exit_2(tmp_path, capsys, args, why):
    video = tmp_path / "clip.mp4"
    video.write_bytes(b"not read: the shape is checked first")
    rc = cli.main(["track", str(video), "--color", "orange", *args, "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and why in err[0], err


def test_a_recommended_file_holds_a_model_per_camera_path_with_its_accuracies_and_reads_format_1(tmp_path):
    import json

    from study.learn.metrics import Interval
    from study.runs import recommended

    data, iv = tmp_path / "data", Interval(0.9, 0.8, 0.95, "test")
    (data / "m").mkdir(parents=True)
    one = recommended.PathModel("velocity, any-camera", (data / "m",), iv, {"exact": iv, "mean": iv}, (0.3, 0.7))
    recommended.save(data, "paper", {recommended.ONE_SCALE: one}, key="abc")
    back = recommended.read(data)
    assert back.key == "abc" and back.path() == dataclasses.replace(one, models=(data / "m",))
    with pytest.raises(ModelError, match="no model for the floor path"):
        back.path("floor")
    with pytest.raises(ValueError, match="unknown camera paths"):
        recommended.save(data, "paper", {"fisheye": one})
    (data / recommended.FILE).write_text(json.dumps({"format": "study.recommended/1", "name": "positions, exact",
                                                    "models": ["m"], "preset": "smoke",
                                                    "val": dataclasses.asdict(iv)}))
    old = recommended.read(data)
    assert old.path().name == "positions, exact" and old.path().accuracy == {} and old.path().band is None


def test_a_bad_choice_is_one_line_and_a_colour_reads_in_any_case(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["classify", "x.mp4", "--color", "purple"])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert e.value.code == 2 and len(err) == 1 and "invalid choice: 'purple'" in err[0], err
    assert "usage:" not in err[0] and err[0].endswith("see study classify --help")
    from study.see.config import TrackConfig

    either = [[b.tolist() for b in TrackConfig(color=c).bounds()] for c in ("Green", "green")]
    assert either[0] == either[1]
    assert cli.build_parser().parse_args(["track", "v.mp4", "--color", "ORANGE"]).color == "orange"


def test_classify_reports_the_missing_video_and_the_missing_size_before_the_model(tmp_path, capsys):
    """No model anywhere, and yet the input's own problems come first: they are what the user must fix."""
    empty = ["--data-dir", str(tmp_path / "no-data")]
    assert cli.main(["classify", str(tmp_path / "gone.mp4"), *empty]) == 2
    assert "gone.mp4: no such file" in one_error_line(capsys)
    video = tmp_path / "throw.mp4"
    video.write_bytes(b"x")
    assert cli.main(["classify", str(video), "--color", "orange", *empty]) == 2
    line = one_error_line(capsys)
    assert "not given for the colour 'orange'" in line and "tennis ball's 0.067 m is assumed only" in line
    assert cli.main(["classify", "--manifest", str(tmp_path / "nodir" / "MANIFEST.csv"), *empty]) == 2
    assert "--manifest " in (line := one_error_line(capsys)) and "nodir/MANIFEST.csv: no such file" in line
    (tmp_path / "bare").mkdir()  # a folder, but no MANIFEST.csv in it: still named by the option
    assert cli.main(["classify", "--manifest", str(tmp_path / "bare"), *empty]) == 2
    assert (line := one_error_line(capsys)).startswith("study: error: --manifest ") and "no MANIFEST.csv" in line


def test_the_commands_help_names_the_video_path():
    text = " ".join(cli.build_parser().format_help().split())
    assert "study track VIDEO" in text and "study classify VIDEO --color C --object-size D" in text


def test_an_options_help_names_the_other_options_by_their_flags():
    """The config's docstrings name fields (``observe_noise``); the command line's help names them as a user types
    them, and keeps any other literal a quoted word."""
    parser = cli.build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    train = " ".join(commands["train"].format_help().split())
    assert "(--observe-noise and the fields after it" in train and "a quarter of --patience epochs" in train
    assert "'cosine'" in train and "'observe_noise'" not in train
    assert "ignored when --hsv is given" in " ".join(commands["track"].format_help().split())
    assert all("``" not in (a.help or "") for c in commands.values() for a in c._actions)


def test_train_help_puts_the_few_options_a_user_needs_first(capsys):
    with pytest.raises(SystemExit):
        cli.main(["train", "--help"])
    out = capsys.readouterr().out
    first, protocol = out.index("what to train (most users set only these)"), out.index("the training protocol")
    assert first < out.index("\n  --observe ") < out.index("\n  --length ") < protocol < out.index("\n  --lr ")
    assert protocol < out.index("\n  --patience ") and first < out.index("\n  --data ") < protocol


def test_a_manifest_takes_the_floor_for_every_clip_and_a_bad_one_is_refused_first(tmp_path, capsys):
    (tmp_path / "a.mp4").write_bytes(b"not read: the floor is checked first")
    (tmp_path / "MANIFEST.csv").write_text("file,label,color,object_size,object_shape\na.mp4,light,orange,0.2,box\n")
    (tmp_path / "FLOOR.csv").write_text("u,v,x,y\n1,2,0,0\n")
    rc = cli.main(["classify", "--manifest", str(tmp_path / "MANIFEST.csv"), "--floor", str(tmp_path / "FLOOR.csv"),
                   "--model", str(tmp_path / "no-model")])
    line = one_error_line(capsys)
    assert rc == 2 and "FLOOR.csv" in line and "four" in line, line
