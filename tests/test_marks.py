"""Floor marks found by their colour (study.see.marks) and drawn into a throw's scene (study.methods.marked): the
blobs found on an inline picture, the pairing with the positions, the layouts and files refused, the throw bitwise
unchanged by its marks, and `study track --floor MARKS.csv` on a rendered clip."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from study import cli
from study.core.errors import ConfigError
from study.methods import marked
from study.see import floor, marklayout, marks, render
from study.see.camera import Camera

RECTANGLE = np.array([[-1.0, -0.75], [1.0, -0.75], [1.0, 0.75], [-1.0, 0.75], [0.0, -0.75], [0.0, 0.75]])
"""A symmetric layout: a rectangle's corners and its long sides' middles (turned half round, it is itself)."""
LEVEL_DOWN = (1.0, 0.0, 0.0, 0.0, 0.2924, -0.9563, 0.0, 0.9563, 0.2924)
"""Camera axes as columns (right, up, back): it looks along +y, tilted about 17 degrees down."""


def _camera() -> Camera:
    return Camera((0.3, -4.0, 1.2), LEVEL_DOWN, 500.0, 640, 360)


def test_find_returns_the_magenta_discs_not_the_floors_light_lines_nor_an_orange_object():
    img = np.full((120, 200, 3), (90, 90, 92), np.uint8)  # BGR grey floor
    img[::20, :] = (215, 230, 230)  # the checker's light edge lines
    img[:, ::25] = (215, 230, 230)
    centres = [(40.0, 30.0), (150.0, 80.0)]
    for u, v in centres:
        cv2.ellipse(img, (int(u), int(v)), (8, 3), 0, 0, 360, (180, 25, 205), -1)  # magenta, BGR
    cv2.circle(img, (100, 60), 6, (20, 90, 230), -1)  # an orange object
    found = marks.find(img)
    assert len(found) == 2
    np.testing.assert_allclose(sorted(map(tuple, found)), sorted(centres), atol=0.1)


def test_match_pairs_found_pixels_with_their_positions_in_any_order():
    cam = _camera()
    px = cam.project(np.column_stack([marklayout.LAYOUT, np.zeros(len(marklayout.LAYOUT))]))
    order = np.random.default_rng(1).permutation(len(px))
    noisy = px[order] + np.random.default_rng(2).normal(0, 0.5, px.shape)
    got = marks.match(noisy, marklayout.LAYOUT, cam.width, cam.height)
    np.testing.assert_array_equal(got.points, marklayout.LAYOUT[order])
    cal = floor.calibrate(got, cam.width, cam.height)
    assert np.linalg.norm(np.subtract(cal.camera.position, cam.position)) < 0.1


def test_a_layout_that_looks_the_same_turned_too_few_marks_or_a_miscount_is_refused():
    cam = _camera()
    px = cam.project(np.column_stack([RECTANGLE, np.zeros(len(RECTANGLE))]))  # a rectangle and its middles
    with pytest.raises(ConfigError, match="look the same turned|looks the same turned"):
        marks.match(px, RECTANGLE, cam.width, cam.height)
    with pytest.raises(ConfigError, match="five or more"):
        marks.match(px[:4], marklayout.LAYOUT[:4], cam.width, cam.height)
    with pytest.raises(ConfigError, match="5 marks found in the video but 6 positions.*tilt the camera down"):
        marks.match(px[:5], marklayout.LAYOUT, cam.width, cam.height)  # a missing mark: why a camera misses one
    with pytest.raises(ConfigError, match="no magenta mark found in the video; check that the marks are in view"):
        marks.match(px[:0], marklayout.LAYOUT, cam.width, cam.height)
    with pytest.raises(ConfigError, match="6 marks found in the video but 5 positions.*nothing else in view"):
        marks.match(px[:6], marklayout.LAYOUT[:5], cam.width, cam.height)


def test_a_positions_only_floor_file_is_read_and_a_bad_one_refused_naming_the_line(tmp_path):
    f = tmp_path / "MARKS.csv"
    f.write_text("x,y\n" + "".join(f"{x},{y}\n" for x, y in marklayout.LAYOUT))
    got = marks.read(f)
    assert marks.needs_finding(got) and np.array_equal(got.points, marklayout.LAYOUT)
    f.write_text("x,y\n0,0\n1,0\n0,1\n1,1\n")
    with pytest.raises(ConfigError, match="MARKS.csv: 4 positions; marks found by their colour need five"):
        marks.read(f)
    f.write_text("x,y\n0,0\n1,zero\n")
    with pytest.raises(ConfigError, match="MARKS.csv, line 3: '1,zero' is not two numbers"):
        marks.read(f)
    f.write_bytes(b"\xef\xbb\xbf" + b"x,y\n" + "".join(f"{x},{y}\n" for x, y in marklayout.LAYOUT).encode())
    assert marks.needs_finding(marks.read(f)), "a spreadsheet's byte-order mark before the header"
    f.write_text("u,v,x,y\n" + "".join(f"{10 * i},{5 * i * i},{x},{y}\n" for i, (x, y) in enumerate(marklayout.LAYOUT)))
    assert not marks.needs_finding(marks.read(f))  # pixels given: read as FLOOR.csv


def test_marks_in_the_scene_leave_the_throw_bitwise_unchanged():
    from study.methods import videos
    from study.simulate import synth

    cfg = synth.SynthConfig.preset("smoke").replace(n_test=2)
    params = synth.sample_split(cfg, 7, "test")
    model, qpos, qvel = videos.throw(cfg, params, 0)
    dressed = marked.with_marks(marked.throw_xml(cfg, params, 0), marklayout.LAYOUT)
    assert dressed.ngeom == model.ngeom + len(marklayout.LAYOUT)
    steps = round(1.5 / model.opt.timestep)
    np.testing.assert_array_equal(render.simulate(dressed, qpos, qvel, steps),
                                  render.simulate(model, qpos, qvel, steps))


@pytest.mark.slow
def test_study_track_and_classify_find_the_marks_in_a_rendered_clip(tmp_path, capsys):
    """Six magenta discs in a 480 x 270 render: found, paired with MARKS.csv, and the camera they give is the
    renderer's within centimetres; `study classify` says it found them."""
    import model_toys
    from study.learn import train

    from study.simulate.scene import Shape, scene_xml

    xml = scene_xml(Shape(), stiffness=render.STIFFNESS, timestep=render.TIMESTEP, rgba=render.OBJECT_RGBA,
                    sleep_tolerance=render.SLEEP_TOLERANCE, **render.CLASS_PARAMS["light"])  # render.class_model's
    model = marked.with_marks(xml, marklayout.LAYOUT)
    qpos, qvel = render.initial_state((-1.0, 0.0, 0.8), (2.0, 0.0, 1.0))
    cfg = render.RenderConfig(width=480, height=270, duration=1.0, noise_std=2.0, jpeg_quality=85, shadows=False)
    clip = render.render(model, qpos, qvel, tmp_path / "throw.mp4", cfg)
    (tmp_path / "MARKS.csv").write_text("x,y\n" + "".join(f"{x:g},{y:g}\n" for x, y in marklayout.LAYOUT))
    rc = cli.main(["track", str(clip.video), "--color", "orange", "--object-size", "0.2", "--object-shape", "box",
                   "--floor", str(tmp_path / "MARKS.csv"), "--no-progress"])
    said = capsys.readouterr().out
    assert rc == 0 and "camera from 6 floor marks" in said and "found in the video" in said, said
    truth = render.scene_camera(model, "side", 480, 270)
    got = floor.calibrate(marks.located(marks.read(tmp_path / "MARKS.csv"), clip.video), 480, 270)
    assert np.linalg.norm(np.subtract(got.camera.position, truth.position)) < 0.1
    assert got.reprojection_px < 1.0
    tm = train.fit(model_toys.dataset(n=16, T=60), train.TrainConfig(dims="z", length=2.0, hidden=8, epochs=1,
                                                                       batch_size=8, truncation=10), progress=False)
    rc = cli.main(["classify", str(clip.video), "--model", str(tm.save(tmp_path / "z")), "--color", "orange",
                   "--object-size", "0.2", "--object-shape", "box", "--floor", str(tmp_path / "MARKS.csv"),
                   "--no-progress"])
    lines = capsys.readouterr().out.strip().splitlines()
    assert rc == 0 and "found in the video" in lines[-1] and "camera from 6 floor marks" in lines[-1], lines
    rc = cli.main(["track", str(clip.video), "--color", "orange", "--out", str(tmp_path / "t.csv"), "--no-progress"])
    rc = cli.main(["classify", str(tmp_path / "t.csv"), "--model", str(tmp_path / "z"), "--object-size", "0.2",
                   "--object-shape", "box", "--floor", str(tmp_path / "MARKS.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and "MARKS.csv: positions only, and t.csv is a track, not a video" in err, err


def test_study_track_reads_the_floor_before_it_tracks(tmp_path, monkeypatch, capsys):
    from study.see import track

    def never(*args, **kwargs):
        raise AssertionError("tracked before the floor was read")

    monkeypatch.setattr(track, "track_video", never)
    (tmp_path / "MARKS.csv").write_text("x,y\n0,0\n1,0\n0,1\n1,1\n")
    (tmp_path / "v.mp4").write_bytes(b"not read")
    rc = cli.main(["track", str(tmp_path / "v.mp4"), "--color", "orange", "--object-size", "0.2", "--floor",
                   str(tmp_path / "MARKS.csv")])
    assert rc == 2 and "MARKS.csv: 4 positions" in capsys.readouterr().err
