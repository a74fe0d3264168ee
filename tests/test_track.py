"""The tracker on rendered video with known ground truth, on synthetic blobs, on every bad input, and on real clips."""

from __future__ import annotations

import csv
from pathlib import Path
import shutil

import cv2
import model_toys
from video_toys import recoloured
import numpy as np
import pytest

from study import cli
from study.chapters import realworld
from study.core.errors import ConfigError, TrackingError, VideoError
from study.learn import train
from study.see import marklayout, render, scale, track, video
from study.see.scale import ObjectShape
from study.simulate import measure

REAL = realworld.real_clips_dir()
FAST = track.TrackConfig(color="orange", progress=False)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory) -> render.Rendered:
    """A light box thrown across the 'side' camera: 1.2 s at 320x240, with blur, noise and JPEG loss."""
    out = tmp_path_factory.mktemp("render") / "throw.mp4"
    model = render.class_model("light")
    qpos, qvel = render.initial_state((-1.5, 0.0, 1.0), (2.5, 0.0, 1.0))
    cfg = render.RenderConfig(width=320, height=240, duration=1.2, blur_subframes=2, noise_std=2.0,
                              jpeg_quality=85, shadows=False)
    return render.render(model, qpos, qvel, out, cfg)


def blob_video(path: Path, centres, size=(160, 120), radius=6, fps=30.0, colour=(0, 90, 230)) -> Path:
    """A grey video with an orange disc at each (u, v) in ``centres`` (None: no disc that frame)."""
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
    for c in centres:
        f = np.full((size[1], size[0], 3), 90, np.uint8)
        if c is not None:
            cv2.circle(f, (int(round(c[0])), int(round(c[1]))), radius, colour, -1, cv2.LINE_8)
        w.write(f)
    w.release()
    return path


def test_rendered_throw_tracked_within_pixels(rendered):
    traj = track.track_video(rendered.video, FAST)
    truth = render.read_truth(rendered.truth)
    assert len(traj.t) == len(truth["t"]) == 36
    m = traj.measured
    err = np.hypot(traj.u - truth["u"], traj.v - truth["v"])[m]
    assert m.mean() >= 0.95
    assert err.mean() < 1.5 and err.max() < 4.0, err


def test_projection_agrees_with_truth_and_camera_axis(rendered):
    model = render.class_model("light")
    data = render.mujoco.MjData(model)
    render.mujoco.mj_forward(model, data)
    cid = render.mujoco.mj_name2id(model, render.mujoco.mjtObj.mjOBJ_CAMERA, "side")
    ahead = data.cam_xpos[cid] - 3.0 * data.cam_xmat[cid].reshape(3, 3)[:, 2]  # 3 m along the view axis
    u, v = render.project(model, data, "side", ahead[None], 320, 240)[0]
    assert (u, v) == pytest.approx((159.5, 119.5), abs=1e-9)
    truth = render.read_truth(rendered.truth)
    np.testing.assert_allclose(np.stack([truth["x"], truth["y"], truth["z"]], 1)[0], [-1.5, 0, 1.0], atol=1e-9)


def test_timestep_must_divide_frame_period():
    from study.simulate.scene import Shape, compile_scene

    m = compile_scene(Shape(), mass=1.0, damping=100, stiffness=2.5e5, friction=0.5, timestep=1 / 1000)
    with pytest.raises(ConfigError, match="does not divide"):
        render.steps_per_frame(m, 30.0)


def test_render_error_names_library(monkeypatch, tmp_path):
    def broken(*a, **k):
        raise RuntimeError("no display")

    monkeypatch.setattr(render.mujoco, "Renderer", broken)
    with pytest.raises(render.RenderError, match="lib"):
        render._renderer(render.class_model("light"), 16, 16)


def test_gap_filled_and_marked(tmp_path):
    centres = [(20 + 4 * i, 60) if i not in (10, 11, 12) else None for i in range(30)]
    traj = track.track_video(blob_video(tmp_path / "gap.mp4", centres), track.TrackConfig(color="orange", max_gap=3, progress=False))
    assert traj.status[10:13].tolist() == [2, 2, 2]  # filled
    assert traj.measured.sum() == 27
    np.testing.assert_allclose(traj.u[10:13], [60, 64, 68], atol=0.6)  # linear between the neighbours
    assert len(traj.segments()) == 1


def test_long_gap_splits(tmp_path):
    centres = [(20 + 4 * i, 60) if not 10 <= i < 20 else None for i in range(30)]
    traj = track.track_video(blob_video(tmp_path / "split.mp4", centres), track.TrackConfig(color="orange", max_gap=3, progress=False))
    segs = traj.segments()
    assert [len(s.t) for s in segs] == [10, 10]
    assert (traj.status[10:20] == 0).all() and np.isnan(traj.u[10:20]).all()  # never invented
    assert traj.longest().t[0] == 0.0


def test_fill_gaps_unit():
    n = 12
    u = np.arange(n, dtype=float)
    u[[3, 6, 7, 8, 9]] = np.nan
    t = track.Trajectory(t=np.arange(n) / 30, u=u, v=u.copy(), status=np.isfinite(u).astype(np.int8),
                         segment=np.zeros(n, np.int32), confidence=np.ones(n), diameter=np.ones(n))
    f = track.fill_gaps(t, max_gap=2)
    assert f.status.tolist() == [1, 1, 1, 2, 1, 1, 0, 0, 0, 0, 1, 1]
    assert f.u[3] == 3.0 and f.segment.tolist() == [0] * 6 + [-1] * 4 + [1, 1]


def test_calibration_and_model_input(tmp_path):
    # A disc 13 px across (radius 6 plus the centre pixel) falling 2 px per frame for 40 frames at 30 fps.
    centres = [(80, 20 + 2 * i) for i in range(40)]
    traj = track.track_video(blob_video(tmp_path / "fall.mp4", centres), FAST, object_size=0.12)
    assert traj.units == "m" and traj.height_per_pixel == pytest.approx(0.12 / 13, rel=0.1)
    assert traj.height[-1] == pytest.approx(0.0, abs=1e-9) and traj.height[0] > 0.6
    x = track.to_model_input(traj, fps=15.0, n_frames=30, rest_height=0.06)
    assert x.shape == (30, 3) and x.dtype == np.float32
    assert (x[:, :2] == 0).all() and (x[20:] == 0).all() and (x[:20, 2] > 0).all()  # 20 rows at 15 fps, zero-padded
    assert x[0, 2] == pytest.approx(traj.height[0] + 0.06, rel=1e-5)
    assert track.to_model_input(traj, fps=30.0, n_frames=10).shape == (10, 3)  # cut


def test_csv_round_trip_and_overlay(rendered, tmp_path):
    traj = track.track_video(rendered.video, FAST, object_size=0.2)
    out = track.write_csv(traj, tmp_path / "t.csv")
    back = track.read_csv(out)
    np.testing.assert_allclose(back.height, traj.height, atol=1e-4, equal_nan=True)
    assert back.units == "m" and (back.status == traj.status).all() and back.fps == pytest.approx(30.0)
    np.testing.assert_allclose(back.diameter, traj.diameter, atol=1e-3, equal_nan=True)  # a pixel track can be scaled
    assert np.isfinite(back.diameter).sum() > 10
    old = tmp_path / "old.csv"  # a file from before the diameter was kept: its first eight columns
    old.write_text("\n".join(",".join(line.split(",")[:8]) for line in out.read_text().splitlines()) + "\n")
    before = track.read_csv(old)
    assert np.isnan(before.diameter).all() and np.allclose(before.height, back.height, equal_nan=True)
    old.unlink()
    ov = track.write_overlay(traj, tmp_path / "ov.mp4")
    assert video.probe(ov).width == 320 and video.probe(ov).frames == len(traj.t)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ov.mp4", "t.csv"]  # no temporary files left


# --- bad input ---------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    with pytest.raises(VideoError, match="no such file"):
        track.track_video(tmp_path / "nope.mp4", FAST)


def test_empty_file(tmp_path):
    (tmp_path / "empty.mp4").write_bytes(b"")
    with pytest.raises(VideoError, match="empty"):
        track.track_video(tmp_path / "empty.mp4", FAST)


def test_text_renamed_mp4(tmp_path):
    (tmp_path / "notes.mp4").write_text("this is not a video\n" * 50)
    with pytest.raises(VideoError, match="notes.mp4"):
        track.track_video(tmp_path / "notes.mp4", FAST)


def test_truncated_mp4(rendered, tmp_path):
    data = rendered.video.read_bytes()
    (tmp_path / "cut.mp4").write_bytes(data[: len(data) // 2])
    with pytest.raises(VideoError, match="truncated"):
        track.track_video(tmp_path / "cut.mp4", FAST)


def test_object_never_found(rendered):
    with pytest.raises(TrackingError, match="never found"):
        track.track_video(rendered.video, track.TrackConfig(color="blue", progress=False))


def test_object_in_too_few_frames(tmp_path):
    centres = [(40, 40) if i < 3 else None for i in range(20)]
    with pytest.raises(TrackingError, match="only 3 of 20"):
        track.track_video(blob_video(tmp_path / "few.mp4", centres), FAST)


@pytest.mark.parametrize("hsv", [(10, 100, 100, 20, 255), (10, 100, 100, 20, 255, 300), (200, 0, 0, 20, 255, 255),
                                 (10, 200, 100, 20, 100, 255), (10.5, 0, 0, 20, 255, 255), ("a", 0, 0, 1, 1, 1)])
def test_malformed_hsv(hsv, rendered):
    with pytest.raises(ConfigError, match="hsv"):
        track.track_video(rendered.video, track.TrackConfig(hsv=hsv, progress=False))


def test_unknown_colour(rendered):
    with pytest.raises(ConfigError, match="color = 'mauve' is not a known colour; choose one of tennis"):
        track.track_video(rendered.video, track.TrackConfig(color="mauve", progress=False))


def test_nothing_written_on_failure(rendered, tmp_path, capsys):
    rc = cli.main(["track", str(rendered.video), "--color", "blue", "--out", str(tmp_path / "t.csv"), "--no-progress"])
    assert rc == 2 and list(tmp_path.iterdir()) == []


# --- command line --------------------------------------------------------------------------------


def test_cli_track_prints_one_line(rendered, tmp_path, capsys):
    out = tmp_path / "t.csv"
    rc = cli.main(["track", str(rendered.video), "--color", "orange", "--out", str(out),
                   "--overlay", str(tmp_path / "o.mp4"), "--no-progress"])
    lines = capsys.readouterr().out.strip().splitlines()
    assert rc == 0 and len(lines) == 1 and "found in" in lines[0]
    rows = list(csv.reader(out.open()))
    assert rows[0][:5] == ["frame", "t_s", "u_px", "v_px", "height_px"] and len(rows) == 37


def test_cli_track_bad_file_exits_2(tmp_path, capsys):
    (tmp_path / "bad.mp4").write_text("not a video")
    rc = cli.main(["track", str(tmp_path / "bad.mp4"), "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and err[0].startswith("study: error:") and "bad.mp4" in err[0]


def test_cli_hsv_out_of_range_exits_2(rendered, capsys):
    rc = cli.main(["track", str(rendered.video), "--hsv", "0", "0", "0", "400", "255", "255", "--no-progress"])
    assert rc == 2 and "hsv" in capsys.readouterr().err


@pytest.fixture(scope="module")
def z_model(tmp_path_factory) -> tuple[Path, train.TrainedModel]:
    """A real Z-only model, trained in a second on toy bounces (what it predicts does not matter here)."""
    cfg = train.TrainConfig(dims="z", length=2.0, hidden=8, epochs=1, batch_size=8, truncation=10)
    tm = train.fit(model_toys.dataset(n=16, T=60), cfg, progress=False)
    return tm.save(tmp_path_factory.mktemp("model") / "z"), tm


def test_cli_classify_video_and_csv(rendered, tmp_path, z_model, capsys):
    """The command prints the model's own answer for the tracked height, in metres (not pixels)."""
    folder, tm = z_model
    rc = cli.main(["classify", "--model", str(folder), str(rendered.video), "--color", "orange",
                   "--object-size", "0.2", "--no-progress"])
    out = capsys.readouterr().out.strip().splitlines()
    traj = track.track_video(rendered.video, FAST, shape=ObjectShape("sphere", (0.2,)), scale_from=scale.DEFAULT)
    x = track.to_model_input(traj, tm.fps, tm.n_frames, rest_height=0.1)
    assert x[:, 2].max() > 0.6  # metres: the box was thrown from 1 m
    p = tm.predict_proba(x[None])[0]
    k = int(p.argmax())
    assert rc == 0 and out[0] == f"{rendered.video}: {('light', 'heavy')[k]} (p(heavy) = {p[1]:.3f}; model {folder})"
    assert len(out) == 3 and out[1].startswith("  trust: "), "how far to trust it"
    assert out[2].startswith("  assumed: scale ") and "RMS over" in out[2], "what it assumed"
    track.write_csv(track.track_video(rendered.video, FAST), tmp_path / "px.csv")
    rc = cli.main(["classify", "--model", str(folder), str(tmp_path / "px.csv")])  # scaled as a video would be:
    assert rc == 0 and "0.067 m over a" in capsys.readouterr().out  # by the object's size (a tennis ball's, unless told)
    old = tmp_path / "old.csv"  # a pixel track from before the blob's size was kept: nothing to scale it by
    old.write_text("\n".join(",".join(r.split(",")[:8]) for r in (tmp_path / "px.csv").read_text().splitlines()))
    rc = cli.main(["classify", "--model", str(folder), str(old)])
    assert rc == 2 and "--metres-per-pixel" in capsys.readouterr().err
    rc = cli.main(["classify", "--model", str(folder), str(tmp_path / "px.csv"), "--metres-per-pixel", "0.01"])
    said = capsys.readouterr().out
    assert rc == 0 and "(p(heavy) = " in said and "a scale you measured" in said


def test_cli_classifies_a_manifest_of_two_colours_and_writes_the_answers(rendered, tmp_path, z_model, capsys):
    folder, tm = z_model
    mine = tmp_path / "mine"
    mine.mkdir()
    shutil.copy(rendered.video, mine / "orange.mp4")
    recoloured(rendered.video, mine / "blue.mp4")
    (mine / "lost.mp4").write_bytes(b"not a video")
    (mine / "MANIFEST.csv").write_text("file,label,color,object_size,object_shape\n"
                                       "orange.mp4,light,orange,0.2,box\n"
                                       "blue.mp4,,90 120 60 130 255 255,0.2,box\n"  # HSV numbers; class not known
                                       "lost.mp4,heavy,orange,0.2,box\n")
    rc = cli.main(["classify", "--manifest", str(mine / "MANIFEST.csv"), "--model", str(folder),
                   "--out", str(tmp_path / "answers.csv"), "--no-progress"])
    out = capsys.readouterr().out
    rows = {r["file"]: r for r in csv.DictReader((tmp_path / "answers.csv").open())}
    assert rc == 0 and list(rows) == ["blue.mp4", "lost.mp4", "orange.mp4"]
    assert rows["orange.mp4"]["label"] == rows["blue.mp4"]["label"] != "", "the same throw in either colour"
    assert abs(float(rows["orange.mp4"]["p"]) - float(rows["blue.mp4"]["p"])) < 0.05
    assert rows["blue.mp4"]["true"] == "" and rows["blue.mp4"]["correct"] == "", "no class given: not scored"
    assert rows["orange.mp4"]["correct"] == str(rows["orange.mp4"]["label"] == "light").lower()
    assert rows["lost.mp4"]["label"] == "" and "lost.mp4" in rows["lost.mp4"]["error"], "the others go on"
    assert "3 videos, 2 classified" in out and "of 1 labelled ones right" in out
    rc = cli.main(["classify", str(rendered.video), "--manifest", str(mine / "MANIFEST.csv")])
    assert rc == 2 and "one of the two" in capsys.readouterr().err
    (mine / "MANIFEST.csv").write_text("file,label,color\norange.mp4,light,purple\n")
    rc = cli.main(["classify", "--manifest", str(mine), "--model", str(folder)])
    assert rc == 2 and "orange.mp4: color 'purple' is unknown" in capsys.readouterr().err


def test_a_video_with_neither_a_size_nor_a_scale_is_refused_not_read_in_pixels(rendered, z_model):
    from study import answer

    folder, _ = z_model
    with pytest.raises(ConfigError, match="heights are in pixels; give the object's size"):
        answer.classify(rendered.video, folder, track_config=FAST, object_shape=None)


def test_cli_classify_rejects_xyz_model(rendered, tmp_path, capsys):
    cfg = train.TrainConfig(dims="xyz", length=0.5, hidden=4, epochs=1, batch_size=8, truncation=5)
    folder = train.fit(model_toys.dataset(n=8, T=15), cfg, progress=False).save(tmp_path / "xyz")
    rc = cli.main(["classify", "--model", str(folder), str(rendered.video), "--color", "orange", "--object-size", "0.2"])
    assert rc == 2 and "'z'" in capsys.readouterr().err


# --- real footage (recorded by others; never copied into the repository) ---------------------------

needs_real = pytest.mark.skipif(not (REAL / "MANIFEST.csv").exists(), reason=f"no real clips at {REAL}")


def _manifest() -> list[dict]:
    return list(csv.DictReader((REAL / "MANIFEST.csv").open())) if (REAL / "MANIFEST.csv").exists() else []


@needs_real
@pytest.mark.slow
@pytest.mark.parametrize("name", [r["file"] for r in _manifest() if r["width"] == "320"] + ["tennis_table_drop.mp4"])
def test_real_clip_ball_found_and_bounces(name):
    traj = track.track_video(REAL / name, track.TrackConfig(color="tennis", progress=False),
                             object_size=realworld.TENNIS_BALL)
    longest = traj.longest()
    # In the 320x240 clips the ball is out of the picture (not yet thrown, above the top, gone) for
    # up to half the frames; inside the throw it is measured in nearly every frame.
    assert traj.found_fraction >= (0.95 if name == "tennis_table_drop.mp4" else 0.45), traj.found_fraction
    assert len(longest.t) >= 40 and longest.measured.mean() >= 0.9
    assert measure.bounce_count(longest.height) >= 2  # the height series of one piece shows at least two bounces


def test_render_is_deterministic(tmp_path):
    model = render.class_model("heavy")
    qpos, qvel = render.initial_state((0.0, 0.0, 0.5), (0.5, 0.0, 0.0), angvel=(1.0, 2.0, 0.0))
    cfg = render.RenderConfig(width=96, height=72, duration=0.3, blur_subframes=2, noise_std=3.0, jpeg_quality=70, shadows=False)
    a = render.render(model, qpos, qvel, tmp_path / "a.mp4", cfg)
    b = render.render(model, qpos, qvel, tmp_path / "b.mp4", cfg)
    assert a.truth.read_bytes() == b.truth.read_bytes()
    assert a.video.read_bytes() == b.video.read_bytes()


def test_reusing_the_image_of_a_resting_object_leaves_the_video_unchanged(tmp_path):
    """A heavy box that lands and falls asleep: its repeated poses reuse the last image, and the mp4
    (noise and JPEG loss included) is byte for byte the one rendered image by image."""
    model = render.class_model("heavy")
    qpos, qvel = render.initial_state((0.0, 0.0, 0.4), (0.5, 0.0, 0.0), angvel=(1.0, 2.0, 0.0))
    cfg = render.RenderConfig(width=96, height=72, duration=1.0, blur_subframes=2, noise_std=3.0, jpeg_quality=70, shadows=False)
    fast = render.render(model, qpos, qvel, tmp_path / "fast.mp4", cfg)
    slow = render.render(model, qpos, qvel, tmp_path / "slow.mp4", cfg, reuse=False)
    assert fast.reused >= 8 and fast.drawn + fast.reused == slow.drawn == 2 * 30 and slow.reused == 0
    assert fast.truth.read_bytes() == slow.truth.read_bytes()
    assert fast.video.read_bytes() == slow.video.read_bytes()


def test_track_and_classify_through_a_floor_the_user_marked(rendered, tmp_path, z_model, capsys, monkeypatch):
    """A FLOOR.csv of six marks around the throw, clicked a pixel off: `study track --floor` gives the rendered
    throw's heights to centimetres at 320 x 240, and `study classify --floor` answers saying what the floor gave."""
    cam = render.scene_camera(render.class_model("light"), "side", 320, 240)
    mid = rendered.xyz[:, :2].mean(axis=0)
    xy = mid + np.array([[-1.0, -0.5], [1.0, -0.5], [1.0, 0.5], [-1.0, 0.5], [0.0, -0.5], [0.0, 0.5]])
    px = cam.project(np.column_stack([xy, np.zeros(6)])) + np.random.default_rng(0).normal(0, 1.0, (6, 2))
    marks = tmp_path / "FLOOR.csv"
    marks.write_text("u,v,x,y\n" + "".join(f"{u:.2f},{v:.2f},{x:.3f},{y:.3f}\n" for (u, v), (x, y) in zip(px, xy)))
    out = tmp_path / "t.csv"
    rc = cli.main(["track", str(rendered.video), "--color", "orange", "--object-size", "0.2", "--object-shape", "box",
                   "--floor", str(marks), "--out", str(out), "--no-progress"])
    said = capsys.readouterr().out
    assert rc == 0 and "camera from 6 floor marks" in said and "px RMS reprojection" in said, said
    got = track.read_csv(out)
    z = got.height + 0.1  # the centre above the floor: the box's rest height is half its edge
    truth = np.interp(got.t, rendered.t, rendered.xyz[:, 2])
    ok = np.isfinite(z) & got.measured
    assert ok.mean() > 0.8 and np.sqrt(np.mean((z[ok] - truth[ok]) ** 2)) < 0.05
    folder, _ = z_model
    rc = cli.main(["classify", str(rendered.video), "--model", str(folder), "--color", "orange", "--object-size",
                   "0.2", "--object-shape", "box", "--floor", str(marks), "--no-progress"])
    lines = capsys.readouterr().out.strip().splitlines()
    assert rc == 0 and "camera from 6 floor marks" in lines[-1] and "the flights between them" in lines[-1], lines
    assert "the blob's size against a 0." in lines[-1], "the answer says it weighed the size"
    rc = cli.main(["track", str(rendered.video), "--color", "orange", "--floor", str(marks), "--no-progress"])
    assert rc == 2 and "--floor: give the object's size" in capsys.readouterr().err
    marks.write_text("u,v,x,y\n1,2,3,4\n")
    rc = cli.main(["track", str(rendered.video), "--color", "orange", "--object-size", "0.2", "--floor", str(marks)])
    assert rc == 2 and "1 marks; give at least 4" in capsys.readouterr().err
    far = [(u + 5000 if i == 0 else u, v) for i, (u, v) in enumerate(px)]  # one mark's pixel off the frame
    marks.write_text("u,v,x,y\n" + "".join(f"{u:.2f},{v:.2f},{x:.3f},{y:.3f}\n" for (u, v), (x, y) in zip(far, xy)))

    def not_yet(*_a, **_k):
        raise AssertionError("tracked before the floor was checked against the frame")

    monkeypatch.setattr(track, "track_video", not_yet)
    for command in (["track", str(rendered.video)], ["classify", str(rendered.video), "--model", str(folder)]):
        rc = cli.main([*command, "--color", "orange", "--object-size", "0.2", "--object-shape", "box", "--floor",
                       str(marks), "--no-progress"])
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and "mark 1 at pixel" in err[0] and "outside the" in err[0], err


def test_marks_given_by_position_that_the_video_does_not_show_are_one_line_saying_none_was_found(rendered, tmp_path,
                                                                                           capsys):
    marks = tmp_path / "MARKS.csv"
    marks.write_text("x,y\n" + "".join(f"{x:g},{y:g}\n" for x, y in marklayout.LAYOUT))
    rc = cli.main(["track", str(rendered.video), "--color", "orange", "--object-size", "0.2", "--object-shape", "box",
                   "--floor", str(marks), "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "no magenta mark found in the video" in err[0], err


def test_sample_floor_points_are_those_the_camera_sees_and_four_are_needed():
    from study.methods import sample
    from study.see.camera import Camera

    level = (1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0)  # columns: right = x, up = z, back = -y: it looks along +y
    cam = Camera((0.0, -4.0, 1.2), level, 400.0, 640, 360)
    assert cam.depth_of(np.zeros((1, 3)))[0] == pytest.approx(4.0), "the floor's middle is in front of it"
    rows = sample.floor_rows(cam)
    assert 4 <= len(rows) <= len(marklayout.LAYOUT)
    assert all(0 <= u <= 639 and 0 <= v <= 359 for u, v, _, _ in rows)
    np.testing.assert_allclose(cam.project(np.array([[x, y, 0.0] for _, _, x, y in rows])),
                               np.array([[u, v] for u, v, _, _ in rows]), atol=1e-9)
    with pytest.raises(ConfigError, match="in the camera's view; need four"):
        sample.floor_rows(cam, marklayout.LAYOUT + 50.0)


def test_the_overlay_joins_found_frames_within_a_piece_never_across_a_filled_gap_or_a_jump(tmp_path):
    from study.see import overlay

    centres = [(20 + 12 * i, 60) for i in range(6)] + [None] * 3 + [(128 + 12 * i, 60) for i in range(4)] \
        + [(250, 20)] + [(250, 20 + 2 * i) for i in range(1, 6)]
    clip = blob_video(tmp_path / "blob.mp4", centres, size=(320, 120))
    traj = track.track_video(clip, track.TrackConfig(color="orange", max_gap=5, progress=False))
    assert (traj.status == 2).sum() == 3 and len(traj.segments()) == 1, "the gap is filled, the jump accepted"
    jump = next(j for j in range(1, len(traj.t)) if traj.u[j] - traj.u[j - 1] > 30)
    assert not overlay.joined(traj, jump) and not any(overlay.joined(traj, j) for j in range(6, 10))
    assert overlay.joined(traj, 3) and overlay.joined(traj, jump + 2)
    out = track.write_overlay(traj, tmp_path / "ov.mp4", tail=len(traj.t))
    last = list(video.frames(out))[-1]
    mid_gap, mid_jump = last[60, 98], last[40, 207]  # halfway along where straight lines would run
    assert np.abs(mid_gap.astype(int) - 90).max() < 25 and np.abs(mid_jump.astype(int) - 90).max() < 25
    assert np.abs(last[60, 50].astype(int) - 90).max() > 60, "the found frames before the gap are joined"


@pytest.mark.parametrize("colour, hue", [("orange", 12), ("red", 0), ("green", 65), ("blue", 115)])
def test_each_object_preset_keeps_a_boxs_shaded_faces(tmp_path, colour, hue):
    """A box of the colour, its upper half lit (V 200), its lower half turned from the light (V 45, as a box's faces
    are under the camera sweep's dim lights): the preset keeps both, so the centre is the box's, not its lit half's
    (4 px higher)."""
    lit, shaded = (cv2.cvtColor(np.uint8([[[hue, 200, v]]]), cv2.COLOR_HSV2BGR)[0, 0].tolist() for v in (200, 45))
    path = tmp_path / f"{colour}.mp4"
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (160, 120))
    for i in range(20):
        f = np.full((120, 160, 3), 150, np.uint8)
        u = 40 + 4 * i
        f[52:60, u - 8:u + 8] = lit
        f[60:68, u - 8:u + 8] = shaded
        w.write(f)
    w.release()
    traj = track.track_video(path, track.TrackConfig(color=colour, progress=False))
    assert traj.measured.all()
    assert np.abs(traj.v - 59.5).max() < 1.0, traj.v  # the box's centre row; the lit half's is 55.5
