"""The camera sweep (study.methods.sweep): shots drawn in their family's ranges, the camera put into the scene as
the code's pinhole sees it, and a smoke sweep rendered and cached."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from study.core import cache
from study.core.errors import ConfigError, OutputError
from study.methods import camera_cost, sweep, tracked, videos
from study.see import render
from study.simulate import measure as motion
from study.see.trajectory import Trajectory
from study.simulate import synth


def test_shots_stay_in_their_familys_ranges():
    rng = np.random.default_rng(0)
    for family, r in sweep.FAMILIES.items():
        for _ in range(20):
            s = sweep.draw_shot(family, rng)
            assert r.height[0] <= s.height <= r.height[1] and r.tilt[0] <= s.tilt <= r.tilt[1]
            assert r.yaw[0] <= abs(s.yaw) <= r.yaw[1] and r.distance[0] <= s.distance <= r.distance[1]
            assert sweep.FOV[0] <= s.fov <= sweep.FOV[1] and s.colour in sweep.COLOURS


def test_the_scene_camera_projects_as_the_shots_pinhole():
    cfg = synth.SynthConfig.preset("smoke").replace(n_test=2)
    params = synth.sample_split(cfg, 5, "test")
    model, qpos, qvel = videos.throw(cfg, params, 0)
    path = render.simulate(model, qpos, qvel, 600)[:, :3]
    shot = sweep.draw_shot("oblique", np.random.default_rng(1))
    cam = sweep.camera(shot, path)
    sweep.dress(model, shot, cam)
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    mine = render.project(model, data, "side", path[::50], shot.width, shot.height_px)
    np.testing.assert_allclose(mine, cam.project(path[::50]), atol=1e-6)


SMOKE = {"per_family": 1, "seed": 2000, "progress": False, "frame_scale": 0.5, "duration": 1.0}
"""A smoke sweep: one clip a family, half-size frames, 1-s clips."""


@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    return synth.SynthConfig.preset("smoke"), sweep.sweep_set(synth.SynthConfig.preset("smoke"), out_dir=out, **SMOKE), out


@pytest.mark.slow
def test_a_smoke_sweep_renders_each_family_once_and_reads_it_back(smoke):
    cfg, clips, out = smoke
    assert [c.shot.family for c in clips] == list(sweep.FAMILIES)
    assert [c.video.label for c in clips] == ["light"] * 4  # one a family: the first class
    assert all(c.video.path.is_file() and c.video.truth.is_file() for c in clips)
    stamp = [c.video.path.stat().st_mtime_ns for c in clips]
    again = sweep.sweep_set(cfg, out_dir=out, **SMOKE)
    assert [c.video.path.stat().st_mtime_ns for c in again] == stamp
    truth = render.read_truth(clips[0].video.truth)
    assert (truth["z"] > 0).all()


class _Says:
    """A stand-in model that answers one class whatever it reads."""

    fps, n_frames = 30.0, 30

    def __init__(self, heavy: bool):
        self.p = np.array([[0.0, 1.0]]) if heavy else np.array([[1.0, 0.0]])

    def predict_proba(self, x):
        return self.p


@pytest.mark.slow
def test_the_camera_cost_scores_every_path_on_the_same_clips(smoke):
    cfg, clips, _ = smoke
    shape = camera_cost.shape_of(cfg)
    tracked = camera_cost.track_clips(clips, shape, progress=False)
    got = camera_cost.measure([_Says(False), _Says(True)], clips, tracked)
    res = got.results
    heights = sorted({c.shot.height_px for c in clips})
    assert list(res) == ["all", *sweep.FAMILIES, *(f"{h}p" for h in heights)], "pooled, by family, by resolution"
    exact = res["all"]["exact"]
    assert exact.accuracy.value == 0.5 and exact.cost is None and exact.rms_mm == 0  # one seed right on each clip
    for name in camera_cost.PATHS:
        r = res["all"][name]
        answered = 1 - r.no_heights / len(clips)
        assert r.accuracy.value == pytest.approx(0.5 * answered)
        assert r.cost.value == pytest.approx(exact.accuracy.value - r.accuracy.value)
        assert got.difference("exact", name).value == pytest.approx(r.cost.value)
    known = res["all"][camera_cost.KNOWN]  # the tracker's pixels through the clip's own camera at the true depth
    assert known.no_heights == 0 and 0 < known.rms_centred_mm < 1000, "every tracked clip, heights in millimetres"
    assert got.difference(camera_cost.KNOWN, camera_cost.FLOOR_PATH).value == pytest.approx(
        known.accuracy.value - res["all"][camera_cost.FLOOR_PATH].accuracy.value)
    print({k: (r.rms_mm, r.rms_centred_mm, r.no_heights) for k, r in res["all"].items()})
    assert res["all"]["rest size"].no_heights == 0, "every smoke clip is tracked"
    assert res["all"]["mean silhouette"].rms_centred_mm < 100, "the heights follow the throw"
    fl = camera_cost.floors(clips, tracked)
    assert fl["all"].clips == len(clips) and 0 <= fl["all"].true_rows < fl["all"].tracked_rows + 0.05
    h = tracked[0]  # on one clip's frames, the best line beats any path
    t, path = h.tracks["rest size"], h.paths["rest size"]
    m = np.isfinite(path)
    best = camera_cost.line_rms(np.where(m, t.v[: len(path)], np.nan), h.exact)
    assert best <= float(np.sqrt(np.mean((path[m] - h.exact[m]) ** 2))) + 1e-9
    assert 0 < camera_cost.size_error(clips, tracked, shape) < 0.5, "the blob is about the object's size"


@pytest.mark.slow
def test_the_drag_rule_on_the_sweep_reads_each_paths_first_fall(smoke):
    cfg, clips, _ = smoke
    tracked = camera_cost.track_clips(clips, camera_cost.shape_of(cfg), progress=False)
    fps, n = 30.0, 30
    x, _ = camera_cost.inputs(clips, tracked, fps, n)
    contact = cfg.shape.bounding_radius
    f_exact = motion.fall_acceleration(x["exact"][..., 2], fps, contact)
    assert np.isfinite(f_exact).all() and (np.abs(f_exact + 9.81) < 2).all(), "the exact first falls are near -g"
    y = np.array([c.video.label == "heavy" for c in clips], int)
    # trained on the exact falls themselves, with the labels flipped on one side of the median: the rule learns
    # that split, and the exact path scores it perfectly against labels that follow it
    split = f_exact > np.median(f_exact)
    for c, heavy in zip(clips, split):
        c.video.label = "heavy" if heavy else "light"
    try:
        acc = camera_cost.drag_rule(f_exact, split.astype(int), clips, x, fps, contact)
    finally:
        for c, lab in zip(clips, y):
            c.video.label = "heavy" if lab else "light"
    assert acc["exact"].value == 1.0 and set(acc) == {"exact", *camera_cost.MEASURED}


def _truth_clip(tmp_path, z, v):
    from types import SimpleNamespace

    n = len(z)
    path = tmp_path / f"truth{len(list(tmp_path.iterdir()))}.csv"
    np.savetxt(path, np.column_stack([np.arange(n) / 30, np.zeros(n), np.zeros(n), z, np.zeros(n), v]),
               delimiter=",", header="t,x,y,z,u,v", comments="")
    return SimpleNamespace(video=SimpleNamespace(truth=path, rest_height=0.1))


def test_one_scale_reaches_a_camera_that_sees_height_alone_and_not_one_that_sees_distance(tmp_path):
    z = 0.1 + np.abs(np.sin(np.linspace(0, 6, 90)))  # centre heights, metres; at rest 0.1
    square_on = _truth_clip(tmp_path, z, 400 - (z - 0.1) / 0.004)
    assert camera_cost.one_scale_floor(square_on) == pytest.approx(0.0, abs=1e-9)
    towards = np.linspace(0, 80, 90)  # the object comes closer: it moves down the picture as it does
    from_above = _truth_clip(tmp_path, z, 400 - (z - 0.1) / 0.004 + towards)
    assert camera_cost.one_scale_floor(from_above) > 0.05


@pytest.mark.slow
def test_every_sweep_clip_shows_its_floor_marks_where_the_floor_path_places_them(smoke):
    """The marks drawn in each clip lie where the camera cost's floor path places them (``sweep.marks_about`` of the
    truth's centres, through the clip's camera): the median frame is magenta at the marks' projections (a far mark
    seen from a low camera may be thinner than a pixel), and marks found by colour land within a pixel of them."""
    import cv2

    from study.see import marklayout, marks

    _, clips, _ = smoke
    found = 0
    for c in clips:
        truth = render.read_truth(c.video.truth)
        world = np.column_stack([truth["x"], truth["y"], truth["z"]])
        cam = sweep.camera(c.shot, world)
        xy = sweep.marks_about(world)
        assert sweep.marks_visible(cam, xy), c.video.path.name
        px = cam.project(np.column_stack([xy, np.zeros(len(xy))]))
        frame = marks.median_frame(c.video.path)
        (h0, s0, v0), (h1, s1, v1) = marklayout.MARK_HSV
        mask = cv2.inRange(cv2.cvtColor(frame, cv2.COLOR_BGR2HSV), (h0, s0, v0), (h1, s1, v1))
        near = [mask[max(0, int(round(v)) - 1): int(round(v)) + 2, max(0, int(round(u)) - 1): int(round(u)) + 2].any()
                for u, v in px]
        assert any(near), f"{c.video.path.name}: no mark drawn where the floor path places them"
        try:
            got = camera_cost.found_floor(c.video, world)
        except ConfigError as e:  # too few to pair at the smoke's half-size frames: the sweep counts it without heights
            assert "marks found in the video but 6 positions given" in str(e) or "fit the image alike" in str(e), e
            continue
        found += 1
        want = cam.project(np.column_stack([got.points, np.zeros(len(got.points))]))
        assert np.abs(got.pixels - want).max() < 1.0, c.video.path.name
    assert found >= len(clips) // 2, f"marks found in {found} of {len(clips)} smoke clips"


@pytest.mark.slow
def test_the_sweeps_camera_and_marks_are_placed_about_the_centres_its_truth_holds(smoke):
    """``sweep.at_frames`` of a throw's simulated path is the truth CSV's centres (to its six decimals), so the
    camera and the marks the camera cost places about the truth are the ones the clip was rendered with."""
    cfg, clips, _ = smoke
    params = sweep.synth_split(cfg.replace(n_test=2 * len(clips)), SMOKE["seed"])
    truths = [render.read_truth(c.video.truth) for c in clips]
    matched = 0
    for i in range(len(params["label"])):
        model, qpos, qvel = videos.throw(cfg, params, i)
        path = render.simulate(model, qpos, qvel, round(SMOKE["duration"] / model.opt.timestep))[:, :3]
        for c, truth in zip(clips, truths):
            frames = sweep.at_frames(model, path, c.shot.fps, SMOKE["duration"])
            xyz = np.column_stack([truth["x"], truth["y"], truth["z"]])
            if frames.shape == xyz.shape and np.allclose(frames, xyz, atol=1e-6, rtol=0):
                matched += 1
                assert np.allclose(sweep.marks_about(frames), sweep.marks_about(xyz), atol=1e-6, rtol=0)
    assert matched == len(clips), f"{matched} of {len(clips)} clips' truth found among the throws' frame paths"


def test_a_path_that_answers_fewer_clips_is_trusted_on_those_it_answered():
    from types import SimpleNamespace

    clips = [SimpleNamespace(video=SimpleNamespace(label="heavy" if i % 2 else "light"),
                             shot=SimpleNamespace(family="low", height_px=480)) for i in range(8)]
    tracked = [camera_cost.Heights(np.zeros(30), {k: np.zeros(30) for k in camera_cost.MEASURED}, {})
               for _ in clips]
    x = {k: np.zeros((8, 30, 3), np.float32) for k in ("exact", *camera_cost.MEASURED)}
    missing = {k: np.zeros(8, bool) for k in x}
    missing[camera_cost.FOUND][:4] = True  # its marks were not found on the first four clips: no answer there
    got = camera_cost.measure([_Says(True)], clips, tracked, (x, missing)).results["all"]  # "heavy" to every clip
    found, exact = got[camera_cost.FOUND], got["exact"]
    assert exact.accuracy.value == exact.answered.value == 0.5
    assert found.no_heights == 4 and found.accuracy.value == 0.25, "a clip without heights is a miss"
    assert found.answered.value == 0.5, "an answer the path gave is right as often as the model is"
    missing[camera_cost.FOUND][:] = True
    assert camera_cost.measure([_Says(True)], clips, tracked, (x, missing)).results["all"][camera_cost.FOUND].answered is None


def _same(a: list[camera_cost.Heights], b: list[camera_cost.Heights]) -> None:
    """Two lists of heights equal to the bit: every array's dtype, shape and bytes, every other field's value."""

    def bits(x, y, what):
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert (x.dtype, x.shape, x.tobytes()) == (y.dtype, y.shape, y.tobytes()), what
        else:
            assert type(x) is type(y) and (x == y or x != x and y != y), what  # NaN equals NaN here

    assert len(a) == len(b)
    for i, (h, k) in enumerate(zip(a, b)):
        bits(h.exact, k.exact, f"clip {i} exact")
        assert list(h.paths) == list(k.paths) and list(h.tracks) == list(k.tracks)
        for name in h.paths:
            bits(h.paths[name], k.paths[name], f"clip {i} path {name}")
        for name in h.tracks:
            for f in dataclasses.fields(Trajectory):
                bits(getattr(h.tracks[name], f.name), getattr(k.tracks[name], f.name), f"clip {i} {name}.{f.name}")


def test_kept_heights_read_back_as_written():
    n = 5
    ramp = np.linspace(0.0, 1.0, n)
    traj = Trajectory(t=ramp, u=ramp * 3, v=np.full(n, np.nan), status=np.ones(n, np.int8),
                      segment=np.zeros(n, np.int32), confidence=ramp, diameter=ramp + 1, fps=np.float64(60.0),
                      source=Path("clip.mp4"), width=np.int64(640), height_px=360, ground_v=np.nan,
                      height_per_pixel=0.01, units="m", z=None, ground_z=0.1)
    h = camera_cost.Heights(ramp.astype(np.float32), {"floor marks": ramp, "floor marks found": "no marks found"},
                            {"floor marks": traj, "known camera": dataclasses.replace(traj, z=ramp)})
    back = tracked.decode(tracked.encode(h))
    assert back.tracks["floor marks"].width == 640 and back.tracks["floor marks"].source == Path("clip.mp4")
    for t in h.tracks.values():  # numpy scalars come back as Python numbers of the same value
        t.fps, t.width = 60.0, 640
    _same([h], [back])


@pytest.mark.slow
def test_the_kept_heights_are_the_plain_loops_to_the_bit_and_read_back_without_tracking(smoke, monkeypatch):
    cfg, clips, _ = smoke
    shape = camera_cost.shape_of(cfg)
    plain = camera_cost.track_clips(clips, shape, progress=False)
    _same(plain, tracked.track_clips(clips, shape, progress=False))  # tracked now, kept, read back

    def tracks_again(*args, **kwargs):
        raise AssertionError("a kept clip was tracked again")

    with monkeypatch.context() as m:
        m.setattr(camera_cost, "heights", tracks_again)
        _same(plain, tracked.track_clips(clips, shape, progress=False))
    bad = tracked.entry(clips[0], shape, cache.source_hash(*cache.closure("study.methods.tracked")))
    bad.write_bytes(b"cut short")  # an entry that cannot be read is made again
    _same(plain, tracked.track_clips(clips, shape, progress=False))
    assert tracked.read(bad).paths.keys() == plain[0].paths.keys()
    for f in bad.parent.glob("*.heights-*.npz"):
        f.unlink()

    def cannot_write(path, data):
        raise OutputError(f"{path}: cannot be written")

    with monkeypatch.context() as m:  # a data folder that cannot be written: tracked, not kept
        m.setattr(cache, "write_bytes_atomic", cannot_write)
        _same(plain, tracked.track_clips(clips, shape, progress=False))
    assert not list(bad.parent.glob("*.heights-*.npz"))
