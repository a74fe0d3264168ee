"""The real-world pipeline (manifests, a rendered set with known classes, classification against the model contract)
and the chapter *Real-world test*'s numbers, tables and sentences from labels made in the test."""

from __future__ import annotations

import dataclasses
import os
from types import SimpleNamespace

import numpy as np
import pytest

from study.book import results
from study.chapters import realworld
from study.chapters.realworld import Recommendation
from study.core.errors import ConfigError, DataError
from study.learn.metrics import Interval
from study.methods import camera_cost
from study.report.text import Table
from study.runs import paper
from study.see import render
from study.simulate import synth


class HeightRangeModel:
    """Stands in for study.train.TrainedModel (same contract): light if the height swings by more than 0.3 m."""

    dims, fps, n_frames = "z", 30.0, 24

    def predict_proba(self, x):
        assert x.ndim == 3 and x.shape[1:] == (self.n_frames, 3) and x.dtype == np.float32
        swing = np.ptp(x[:, :, 2], axis=1)
        p_heavy = 1 / (1 + np.exp(30 * (swing - 0.3)))
        return np.stack([1 - p_heavy, p_heavy], axis=1)


@pytest.fixture(scope="module")
def rendered_set(tmp_path_factory):
    cfg = synth.SynthConfig.preset("smoke")
    rcfg = render.RenderConfig(width=160, height=120, duration=0.8, shadows=False)
    return realworld.render_set(cfg, 1, 1000, tmp_path_factory.mktemp("rw"), rcfg, progress=False)


@pytest.mark.slow  # renders the set (about 5 s), shared with the tests below
def test_render_set_labels_truth_and_cache(rendered_set, tmp_path):
    assert [v.label for v in rendered_set] == ["light", "heavy"]
    for v in rendered_set:
        truth = render.read_truth(v.truth)
        assert len(truth["t"]) == 24 and np.allclose(truth["y"][:5], 0.0, atol=0.01)  # thrown across the view
    mtimes = [v.path.stat().st_mtime_ns for v in rendered_set]
    cfg = synth.SynthConfig.preset("smoke")
    rcfg = render.RenderConfig(width=160, height=120, duration=0.8, shadows=False)
    again = realworld.render_set(cfg, 1, 1000, rendered_set[0].path.parents[1], rcfg, progress=False)
    assert [v.path.stat().st_mtime_ns for v in again] == mtimes  # reused, not re-rendered


def test_classify_rows_and_accuracy(rendered_set):
    rows = realworld.classify(HeightRangeModel(), rendered_set, progress=False)
    assert [r.file for r in rows] == [v.path.name for v in rendered_set]
    for r in rows:
        assert r.tracked and 0.9 <= r.found <= 1.0 and r.p_light + r.p_heavy == pytest.approx(1.0)
    acc = realworld.per_class_interval(rows)
    assert set(acc) == {"light", "heavy"}
    for c, iv in acc.items():
        k = sum(r.correct for r in rows if r.label == c)
        assert iv.value == k / 1 and iv.lo <= iv.value <= iv.hi and "Wilson" in iv.method
    err = realworld.tracking_error(rendered_set)
    assert err.found >= 0.9 and err.mean_px < 3.0


def test_height_factor_reaches_the_model(rendered_set):
    seen = []

    class Spy(HeightRangeModel):
        def predict_proba(self, x):
            seen.append(x[0, :, 2].copy())
            return super().predict_proba(x)

    tracks = realworld.track_all(rendered_set[:1], progress=False)
    realworld.classify(Spy(), rendered_set[:1], tracks, height_factor=1.0, progress=False)
    realworld.classify(Spy(), rendered_set[:1], tracks, height_factor=2.0, progress=False)
    rest = rendered_set[0].rest_height
    n = np.count_nonzero(seen[0])
    np.testing.assert_allclose(seen[1][:n] - rest, 2 * (seen[0][:n] - rest), rtol=1e-5, atol=1e-6)


def test_xyz_model_refused(rendered_set):
    class XYZ(HeightRangeModel):
        dims = "xyz"

    with pytest.raises(ConfigError, match="'z'"):
        realworld.classify(XYZ(), rendered_set, progress=False)


def test_manifest_errors(tmp_path):
    with pytest.raises(DataError, match="no such folder"):
        realworld.read_manifest(tmp_path / "nope")
    (tmp_path / "list.csv").write_text("file,label\n")
    with pytest.raises(DataError, match="is a file; give the folder"):  # said "no such folder" before
        realworld.read_manifest(tmp_path / "list.csv")
    with pytest.raises(DataError, match="MANIFEST.csv"):
        realworld.read_manifest(tmp_path)
    (tmp_path / "MANIFEST.csv").write_text("file,label\na.mp4,bouncy\n")
    with pytest.raises(DataError, match="a.mp4"):
        realworld.read_manifest(tmp_path)
    (tmp_path / "a.mp4").write_bytes(b"x")
    assert [(v.path.name, v.label) for v in realworld.read_manifest(tmp_path)] == [("a.mp4", "light")]
    (tmp_path / "MANIFEST.csv").write_text("file,label\na.mp4,squishy\n")
    with pytest.raises(ConfigError, match="squishy"):
        realworld.read_manifest(tmp_path)


@pytest.mark.slow  # uses the rendered set
def test_the_chapter_reads_a_folder_of_two_colours_and_answers_each_clip(rendered_set, tmp_path):
    """A reader's own folder: one clip in the renders' orange, one recoloured blue and given as six HSV numbers with
    no class; the chapter's functions track each by its own colour, score only the labelled one, and write every
    clip's answer as a CSV."""
    import csv
    import shutil

    from video_toys import recoloured

    light = rendered_set[0]
    shutil.copy(light.path, tmp_path / "orange.mp4")
    recoloured(light.path, tmp_path / "blue.mp4")
    size = light.object_size
    (tmp_path / "MANIFEST.csv").write_text(f"file,label,color,object_size\norange.mp4,light,orange,{size}\n"
                                           f"blue.mp4,?,90 120 60 130 255 255,{size}\n")
    clips = realworld.real_clips(tmp_path)
    assert [(v.path.name, v.label, v.hsv is not None) for v in clips] == [("blue.mp4", None, True),
                                                                            ("orange.mp4", "light", False)]
    rows = realworld.classify(HeightRangeModel(), clips, realworld.track_all(clips, progress=False), progress=False)
    assert all(r.tracked for r in rows) and rows[0].predicted == rows[1].predicted, "one throw, either colour"
    acc = realworld.per_class_interval(rows)
    assert acc["heavy"] is None and acc["light"].value in (0.0, 1.0), "the clip with no class is not scored"
    table = realworld._real_table(rows)
    assert [r["true"] for r in table.rows] == ["not known", "light"]
    written = list(csv.DictReader(table.write_csv(tmp_path / "out" / "answers.csv").open()))
    assert [r["file"] for r in written] == ["blue.mp4", "orange.mp4"] and written[1]["label"] == rows[1].predicted


def test_untrackable_video_is_a_row_not_a_crash(tmp_path):
    bad = tmp_path / "bad.mp4"
    bad.write_text("not a video")
    rows = realworld.classify(HeightRangeModel(), [realworld.Video(bad, "light")], progress=False)
    assert not rows[0].tracked and "bad.mp4" in rows[0].error and not rows[0].correct
    assert realworld.per_class_interval(rows)["light"] is None  # nothing classified, no interval


@pytest.mark.slow
def test_rendered_motion_is_the_datasets_trajectory(smoke_cfg, smoke_dataset):
    cfg, split = smoke_cfg, smoke_dataset.train
    model, qpos, qvel = render.synth_model(cfg, split.params, 0)
    states = render.simulate(model, qpos, qvel, 30 * cfg.steps_per_frame)
    np.testing.assert_allclose(states[:: cfg.steps_per_frame, :3][:30], split.x[0, :30], atol=1e-6)
    frames = render.filmstrip(cfg, split.params, 0, [0.0, 0.5], width=64, height=48)
    assert [f.shape for f in frames] == [(48, 64, 3)] * 2 and frames[0].dtype == np.uint8


@pytest.mark.slow
def test_renders_without_mujoco_gl_in_the_environment():
    """A plain `python` with MUJOCO_GL unset renders too: importing study sets the headless default
    before any module imports mujoco (mujoco reads it once, at its first import)."""
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    code = ("from study import synth, render\nimport mujoco\n"
            "m = render.class_model('light'); d = mujoco.MjData(m); mujoco.mj_forward(m, d)\n"
            "r = render._renderer(m, 24, 32); r.update_scene(d, camera='side'); print(r.render().shape)")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "(24, 32, 3)"


def test_class_model_refuses_a_sleep_tolerance_that_would_freeze_a_throw_in_mid_air():
    limit = synth.max_sleep_tolerance(render.TIMESTEP)
    assert render.class_model("heavy", sleep_tolerance=limit).opt.sleep_tolerance == pytest.approx(limit)
    with pytest.raises(ConfigError, match="sleep_tolerance"):
        render.class_model("heavy", sleep_tolerance=2 * limit)
    with pytest.raises(ConfigError, match="sleep_tolerance"):
        render.class_model("heavy", sleep_tolerance=-1e-3)


# ---------------------------------------------------------------------------------------------
# The chapter's numbers, tables and sentences, from labels made here (no video, no model)


def _label(file: str, label: str, predicted: str = "", error: str = "") -> realworld.Label:
    if error:
        return realworld.Label(file, label, error)
    p_light = 0.8 if predicted == "light" else 0.3
    return realworld.Label(file, label, "", 30, 0.9, 1, 1, 2, 0.01, p_light, 1 - p_light, predicted)


RENDERED = [_label("light_000.mp4", "light", "light"), _label("light_001.mp4", "light", "heavy"),
            _label("heavy_002.mp4", "heavy", "heavy"), _label("heavy_003.mp4", "heavy", error="lost it")]
REAL = [_label("ball.mp4", "light", "light"), _label("ball2.mp4", "light", error="not found")]
NAMES = [f"{i}, {t}" for i in ("positions", "velocity") for t in ("exact", "randomised", "any-camera")]


def _rec(choice: str = "velocity, randomised") -> Recommendation:
    val = {n: Interval(0.5 + 0.05 * i, 0.4, 0.9, "bootstrap") for i, n in enumerate(NAMES)}
    user = {n: Interval(0.45 + 0.04 * i, 0.3, 0.9, "bootstrap") for i, n in enumerate(NAMES)}
    return Recommendation(choice, val, user, {})


def test_the_numbers_keep_their_names_follow_the_labels_and_read_back(tmp_path):
    labels = {"table1": ("Table 1's Z model", RENDERED, REAL),
              "recommended": ("recommended (velocity, randomised)", RENDERED[:2], [])}
    n = realworld.reported(_rec(), labels)
    names = [name for name, _ in n.entries()]
    assert {"realworld.figure1", "realworld.figure5", "realworld.figure6", "realworld.table1.rendered.light",
            "realworld.table1.rendered.heavy", "realworld.table1.real.light",
            "realworld.candidate.velocity.randomised.val", "realworld.recommended.rendered.light"} <= set(names)
    assert "realworld.table1.real.heavy" not in names, "no real heavy clip: no number"
    assert "realworld.recommended.rendered.heavy" not in names, "no heavy video classified: no number"
    light, heavy = n.models["table1"].rendered["light"], n.models["table1"].rendered["heavy"]
    assert light.value == 0.5 and "1 of 2" in light.method and heavy.value == 1.0 and "1 of 1" in heavy.method
    assert light.paper == paper.REAL_WORLD["light"] and heavy.paper == paper.REAL_WORLD["heavy"]
    assert light.verdict == "not comparable" and "rendered MuJoCo" in light.decision.reason
    real = n.models["table1"].real["light"]
    assert real.value == 1.0 and "tennis balls" in real.decision.reason
    assert n.candidate["velocity"]["exact"].val.value == pytest.approx(0.65)
    assert n.candidate["velocity"]["exact"].val_user.value == pytest.approx(0.57)
    assert n.figure5.verdict == "qualitative" and n.models["table1"].rendered["light"].what == (
        "rendered light videos classified correctly, Table 1's Z model")
    f = tmp_path / "results.json"
    f.write_text(results.dumps(n.entries()))
    assert realworld.Numbers.read(results.load(f)) == n


def test_the_tables_show_the_paper_beside_ours_and_say_when_there_is_no_footage():
    numbers = realworld.reported(_rec(), {"table1": ("Table 1's Z model", RENDERED, REAL)})
    acc = realworld._acc_table({"Table 1's Z model": (numbers.models["table1"], REAL)}, 2)
    md = acc.markdown()
    assert "93 % (golf ball, real)" in md and "100 % (wooden cube, real)" in md and "(2 per class)" in md
    assert "100.0 % [" in md and "(tennis balls, n = 2)" in md and "no footage" in md and "not comparable" in md
    real = realworld._real_table(REAL)
    assert [r["label"] for r in real.rows] == ["light", "not tracked: not found"] and real.rows[1]["found"] == "—"
    assert realworld._real_table([]).markdown() == "*No real clips were found.*"
    val = realworld._val_table(_rec("positions, randomised")).rows
    assert [r["chosen"] for r in val] == ["", "✓", "", "", "", ""] and val[1]["user"].startswith("49.0 %")


def test_per_class_accuracy_counts_only_the_videos_tracked_and_the_scale_error_is_a_median():
    acc = realworld.per_class_interval(RENDERED)
    assert acc["light"].value == 0.5 and acc["heavy"].value == 1.0 and "1 of 1" in acc["heavy"].method
    assert realworld.per_class_interval(RENDERED[3:])["heavy"] is None
    tracks = [realworld.Tracked(SimpleNamespace(height_per_pixel=s)) for s in (0.011, 0.009, 0.0125)]
    assert realworld.scale_error(tracks + [realworld.Tracked(None, "lost")], 0.01) == pytest.approx(0.1)


def _iv(v: float, lo: float | None = None, hi: float | None = None) -> Interval:
    return Interval(v, v - 0.05 if lo is None else lo, v + 0.05 if hi is None else hi, "bootstrap")


def _result(numbers: realworld.Numbers, choice: str) -> realworld.RealWorld:
    empty = Table([], {})
    return realworld.RealWorld(numbers, (), (), _rec(choice), realworld.PixelError(2.14, 4.16, 0.987), (), (), (),
                               empty, empty, empty, empty, empty, 2, 0, 30, "1", "320×240", "8.4 %", empty, empty)


def test_a_users_path_on_the_books_videos_reads_back_and_its_sentences_follow_it(tmp_path):
    n = realworld.reported(_rec(), {"table1": ("Table 1's Z model", RENDERED, REAL)}, {"table1": RENDERED},
                           {"table1": RENDERED[:3]})
    names = [name for name, _ in n.entries()]
    assert {"realworld.user.table1.light", "realworld.exact.table1.heavy"} <= set(names)
    assert not any(".sweep." in name for name in names), "the camera sweep is the next chapter's"
    assert n.user["table1"]["light"].verdict == "not comparable"
    f = tmp_path / "results.json"
    f.write_text(results.dumps(n.entries()))
    assert realworld.Numbers.read(results.load(f)) == n
    r = _result(n, "velocity, randomised")
    assert r.user_words.startswith("on a user's path, with no camera, it labels 50.0 % [")
    assert r.user_words.endswith("(by the renderer's camera: 50.0 %, 100.0 %; from the throws' exact heights: "
                                 "50.0 %, 100.0 %)")
    assert r.real_count_words == "none were found here"
    limited = dataclasses.replace(r, real=(None, None), real_found=6)
    assert limited.real_count_words == "the first 2 of the folder's 6 clips (this preset keeps 2)"
    mine = realworld.reported(_rec(), {"table1": ("your model", RENDERED, REAL)}, objects="orange balls")
    assert "orange balls filmed by others" in mine.models["table1"].real["light"].decision.reason
    assert "(orange balls, n = 2)" in realworld._acc_table({"your model": (mine.models["table1"], REAL)}, 2,
                                                            "orange balls").markdown()
    t = realworld._render_heights_table({k: (30.0, 20.0) for k in camera_cost.PATHS}).rows
    assert [r["path"] for r in t if "(default)" in r["path"]] == ["mean silhouette (default)"]
    assert t[0]["book"] == "20 (30)"


def test_the_sentences_follow_the_numbers():
    only = realworld.reported(_rec(), {"table1": ("Table 1's Z model", RENDERED, [])})
    assert "no rendered video could be tracked" in _result(only, "positions, exact").user_words
    r = _result(only, "positions, exact")
    assert r.choice_text == "the recommended one, which is Table 1's model itself"
    assert r.real_words == "no real clips were found to classify"
    assert (r.err_mean, r.err_p95, r.found_rendered) == ("2.1", "4.2", "98.7 %")
    both = realworld.reported(_rec(), {"table1": ("Table 1's Z model", RENDERED, REAL),
                                       "recommended": ("recommended (velocity, randomised)", RENDERED, REAL)})
    r = _result(both, "velocity, randomised")
    assert r.choice_text == "the recommended one, velocity, randomised"
    assert r.real_words.startswith("of the real clips (light), it labels 100.0 % [")


def test_real_clips_from_a_manifest_or_none(tmp_path, monkeypatch):
    for name in ("b.mp4", "a.mp4", "c.mp4"):
        (tmp_path / name).write_bytes(b"x")
    (tmp_path / "MANIFEST.csv").write_text("file,label\nb.mp4,ball\na.mp4,cube\nc.mp4,light\n")
    clips = realworld.real_clips(tmp_path, "orange", 0.1, limit=2)
    assert [(v.path.name, v.label, v.color, v.rest_height) for v in clips] == [("a.mp4", "heavy", "orange", 0.05),
                                                                              ("b.mp4", "light", "orange", 0.05)]
    empty = tmp_path / "empty"
    empty.mkdir()
    monkeypatch.setenv(realworld.REAL_CLIPS_ENV, str(empty))
    assert realworld.real_clips() == [], "no footage beside the project: no real clips, no error"
    with pytest.raises(DataError, match="MANIFEST.csv"):
        realworld.real_clips(empty)  # a folder the reader named must hold a manifest


def test_every_real_clip_is_credited_to_where_it_came_from(tmp_path):
    (tmp_path / "a.mp4").write_bytes(b"x")
    (tmp_path / "b.mp4").write_bytes(b"x")
    (tmp_path / "MANIFEST.csv").write_text(
        "file,label,object,source_repository,source_commit,source_path,licence\n"
        "a.mp4,bouncy,a tennis ball,someone/clips,85eec8e,res/a.mp4,none stated\nb.mp4,bouncy,,,,,\n")
    only = realworld.reported(_rec(), {"table1": ("Table 1's Z model", RENDERED, [])})
    r = dataclasses.replace(_result(only, "positions, exact"), real=tuple(realworld.real_clips(tmp_path)))
    rows = r.credits.rows
    assert rows[0] == {"file": "a.mp4", "source": "someone/clips 85eec8e res/a.mp4", "licence": "none stated"}
    assert rows[1]["source"] == rows[1]["licence"] == "not stated", "a clip without a source says so"
    assert "No real clips" in _result(only, "positions, exact").credits.markdown()


def test_a_manifest_is_read_strictly_an_unknown_column_a_colour_in_any_case_no_silent_tennis_size(tmp_path):
    """A misspelt header is refused naming the column, its likely meaning and the known ones; a colour's name reads
    in any case; an object of another colour with no size is refused, not scaled as a tennis ball."""
    (tmp_path / "a.mp4").write_bytes(b"x")
    m = tmp_path / "MANIFEST.csv"
    m.write_text("file,lable,colour\na.mp4,light,orange\n")
    with pytest.raises(ConfigError, match=r"column 'lable' is unknown \(did you mean 'label'\?\); its columns are "
                                          r"file, label, color, object_size, object_shape"):
        realworld.read_manifest(tmp_path)
    m.write_text("file,label,color,object_size\na.mp4,light,Orange,0.2\n")
    assert realworld.read_manifest(tmp_path)[0].color == "orange"
    m.write_text("file,label,color\na.mp4,light,orange\n")
    with pytest.raises(ConfigError, match="a.mp4: no object_size for an object that is not tennis-yellow"):
        realworld.read_manifest(tmp_path)
    assert realworld.read_manifest(tmp_path, object_size=0.2)[0].object_size == 0.2, "one size for every row"
    m.write_text("file,label\na.mp4,light\n")
    assert realworld.read_manifest(tmp_path)[0].object_size == 0.067, "the tennis colour: a tennis ball"
    m.write_text("file,label,object,source_repository,licence\na.mp4,light,a ball,someone/repo,none stated\n")
    assert realworld.read_manifest(tmp_path)[0].info["licence"] == "none stated", "the shared clips' notes are kept"
    with pytest.raises(DataError, match="--manifest .*nope: no such folder"):
        realworld.read_manifest(tmp_path / "nope", what="--manifest")


def test_a_readers_folder_keeps_every_clip_and_the_shared_clips_a_presets_few(tmp_path):
    clips = [realworld.Video(tmp_path / f"{i}.mp4", "light") for i in range(4)]
    assert realworld.shown(clips, str(tmp_path), 2) == clips, "a folder the reader gave: every clip"
    assert realworld.shown(clips, "", 2) == clips[:2], "the shared clips: the preset's few"


def test_the_floor_models_labels_through_floor_marks_read_back_and_show_as_counts(tmp_path):
    """The model recommended for the floor path, on the book's renders through floor marks beside the renderer's
    camera: stored under realworld.floor.<model>.<class>, read back, and a table column of counts per class."""
    n = realworld.reported(_rec(), {"table1": ("Table 1's Z model", RENDERED, REAL),
                                    "floor": ("recommended for floor marks (heights, floor)", RENDERED, REAL)},
                           floor={"floor": RENDERED[:3]})
    assert "realworld.floor.floor.light" in {name for name, _ in n.entries()}
    right = {c: sum(r.correct for r in ls if r.label == c) for c, ls in (("light", RENDERED[:3]), ("heavy", RENDERED))}
    gap = n.floor_minus_known["floor"]  # against the same model's labels by the renderer's camera
    assert gap["light"].value == right["light"] - sum(r.correct for r in RENDERED if r.label == "light")
    assert set(gap) == {c for c in ("light", "heavy") if any(r.label == c for r in RENDERED[:3])}
    f = tmp_path / "results.json"
    f.write_text(results.dumps(n.entries()))
    assert realworld.Numbers.read(results.load(f)) == n
    table = realworld._user_table({"floor model": (RENDERED, RENDERED, RENDERED, RENDERED[:3])})
    light, heavy = table.rows
    right = sum(r.correct for r in RENDERED[:3] if r.label == "light")
    assert light["floor"].startswith(f"{right}/{sum(r.label == 'light' for r in RENDERED[:3])} (")
    assert "floor marks" in table.columns["floor"] and heavy["class"] == "heavy"


def test_two_chapters_rendering_the_same_set_at_once_render_each_video_once(tmp_path, monkeypatch):
    """Two chapters of a build ask for the book's videos at the same moment: each video is made once, the second
    waits for it (``cache.one_maker``) and reads it. A fake renderer counts the calls and is slow enough to overlap."""
    import threading
    import time

    from study.methods import videos

    calls: list[str] = []

    def fake_render(model, qpos, qvel, out, cfg=None, reuse=True):
        calls.append(str(out))
        time.sleep(0.2)
        out = os.fspath(out)
        for path in (out, out[: -len(".mp4")] + ".csv"):
            with open(path, "w") as f:
                f.write("made once\n")

    monkeypatch.setattr(videos.render, "render", fake_render)
    cfg = synth.SynthConfig.preset("smoke")
    rcfg = render.RenderConfig(width=160, height=120, duration=0.8, shadows=False)
    made = []
    both = [threading.Thread(target=lambda: made.append(videos.render_set(cfg, 2, 1000, tmp_path, rcfg, progress=False)))
            for _ in range(2)]
    for t in both:
        t.start()
    for t in both:
        t.join()
    assert len(made) == 2 and [v.path for v in made[0]] == [v.path for v in made[1]]
    assert sorted(calls) == sorted({v.path.as_posix() for v in made[0]}), "each video rendered once, not twice"
