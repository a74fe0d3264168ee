"""A camera the floor calibrates (study.see.floor): floor marks read strictly, the camera recovered from them, and a
tumbling throw's heights from its pixels -- one that leaves its vertical plane at every bounce, which the one-plane
path (study.see.ground) cannot follow. Inline scenes: the camera and the throw are made here, the answer known."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest
import scripts_toys

from study.core.errors import ConfigError, DataError
from study.methods import sweep
from study.see import floor
from study.see.config import COLORS
from study.see.geometry import G
from study.see.scale import ObjectShape
from study.see.trajectory import Trajectory

RECTANGLE = np.array([[-1.0, -0.75], [1.0, -0.75], [1.0, 0.75], [-1.0, 0.75], [0.0, -0.75], [0.0, 0.75]])
"""Floor marks about the throw's middle, metres: a 2 m x 1.5 m rectangle's corners and its long sides' middles."""
REST = 0.1


def tumbling_throw(fps: float = 60.0, seconds: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """Times (n,) and centres (n, 3) metres of a throw that turns at each bounce (its horizontal velocity swung by
    25 degrees and slowed), then slides to rest: never in one vertical plane."""
    dt = 1.0 / fps / 40
    p, vel = np.array([-1.0, -0.2, 1.0]), np.array([1.6, 0.2, 1.0])
    out, turn = [], 1.0
    for _ in range(int(fps * seconds)):
        out.append(p.copy())
        for _ in range(40):
            if p[2] > REST or vel[2] > 0:
                vel[2] -= G * dt
            else:  # sliding: friction slows it
                h = np.linalg.norm(vel[:2])
                vel[:2] *= max(0.0, h - 3.0 * dt) / h if h > 0 else 0.0
            p = p + vel * dt
            if p[2] < REST:
                p[2] = REST
                if vel[2] < -0.6:  # a bounce: up again, turned
                    c, s = np.cos(np.radians(25 * turn)), np.sin(np.radians(25 * turn))
                    vel[:2] = 0.7 * np.array([[c, -s], [s, c]]) @ vel[:2]
                    vel[2], turn = -0.5 * vel[2], -turn
                else:
                    vel[2] = 0.0
    return np.arange(len(out)) / fps, np.array(out)


def scene(height: float, tilt: float, yaw: float, path: np.ndarray):
    shot = sweep.Shot(family="test", height=height, tilt=tilt, yaw=yaw, distance=4.0, fov=60.0, width=1280,
                      height_px=720, fps=60.0, colour="red", floor=sweep.FLOORS[0], light=0.8)
    return sweep.camera(shot, path)


def marks(cam, path: np.ndarray, noise: float, k: int = 6, seed: int = 0) -> floor.Floor:
    """``k`` floor marks around the throw (a 2 m x 1.5 m rectangle's corners, then points on its sides), their pixels
    as a careful click gives them: the exact projection plus ``noise`` pixels."""
    mid = path[:, :2].mean(axis=0)
    return floor.seen(cam, RECTANGLE[:k] + mid, noise, seed)


@pytest.mark.parametrize("height, tilt, yaw", [(1.0, 5.0, 0.0), (1.7, 30.0, -45.0), (2.0, 40.0, 30.0),
                                               (0.6, 10.0, 50.0)])
def test_a_floor_calibrated_camera_gives_a_tumbling_throws_heights(height, tilt, yaw):
    t, path = tumbling_throw()
    cam = scene(height, tilt, yaw, path)
    assert np.ptp(path[:, 1]) > 0.1, "the throw leaves its vertical plane"
    cal = floor.calibrate(marks(cam, path, 0.0), cam.width, cam.height)
    np.testing.assert_allclose(cal.camera.position, cam.position, atol=1e-4)
    assert cal.reprojection_px < 1e-3 and "camera from 6 floor marks" in cal.note()
    uv = cam.project(path)
    z = floor.heights(cal.camera, t, uv[:, 0], uv[:, 1], REST)
    assert np.isfinite(z).mean() > 0.95
    assert np.sqrt(np.nanmean((z - path[:, 2]) ** 2)) < 0.01, "exact marks and pixels: under a centimetre"
    noisy = floor.calibrate(marks(cam, path, 1.0), cam.width, cam.height)
    jitter = np.random.default_rng(1).normal(0.0, 0.3, uv.shape)  # a tracker's sub-pixel centroid
    z = floor.heights(noisy.camera, t, uv[:, 0] + jitter[:, 0], uv[:, 1] + jitter[:, 1], REST)
    assert np.sqrt(np.nanmean((z - path[:, 2]) ** 2)) < 0.03, "a pixel's clicking error: centimetres"
    assert 0.3 < noisy.reprojection_px < 3


def test_a_bad_floor_is_refused_naming_the_file_and_the_problem(tmp_path):
    f = tmp_path / "FLOOR.csv"
    with pytest.raises(DataError, match="FLOOR.csv: no such file; write a CSV with the header u,v,x,y"):
        floor.read_floor(f)
    f.write_text("")
    with pytest.raises(DataError, match="empty"):
        floor.read_floor(f)
    f.write_text("x,y,u,v\n1,2,3,4\n")
    with pytest.raises(ConfigError, match="header 'x,y,u,v'; it must be u,v,x,y"):
        floor.read_floor(f)
    f.write_text("u,v,x,y\n1,2,3,four\n")
    with pytest.raises(ConfigError, match="line 2: '1,2,3,four' is not four numbers"):
        floor.read_floor(f)
    f.write_text("u,v,x,y\n10,10,0,0\n20,10,1,0\n20,20,1,1\n")
    with pytest.raises(ConfigError, match="3 marks; give at least 4"):
        floor.read_floor(f)
    f.write_text("u,v,x,y\n10,10,0,0\n20,10,1,0\n30,10,2,0\n40,10,3,0\n")
    with pytest.raises(ConfigError, match="on one line on the floor"):
        floor.read_floor(f)
    t, path = tumbling_throw()
    cam = scene(1.7, 30.0, -45.0, path)
    four = marks(cam, path, 0.0, k=4)
    f.write_text("u,v,x,y\n" + "".join(f"{u},{v},{x},{y}\n" for (u, v), (x, y) in zip(four.pixels, four.points)))
    read = floor.read_floor(f)
    assert "four marks fit any camera exactly" in floor.calibrate(read, cam.width, cam.height).note()
    with pytest.raises(ConfigError, match=r"mark \d at pixel \(.*\) is outside the 320 x 240 image"):
        floor.calibrate(read, 320, 240)
    upside_down = floor.Floor(np.column_stack([read.pixels[:, 0], cam.height - 1 - read.pixels[:, 1]]), read.points)
    with pytest.raises(ConfigError, match="below the floor"):  # the image flipped: the floor is seen from beneath
        floor.calibrate(upside_down, cam.width, cam.height)


def test_a_flight_whose_landing_is_never_seen_is_left_unknown_not_put_on_the_floor():
    """Cut before the first landing: a flight and no contact. Its frames cannot be placed; none is reported at rest."""
    t, path = tumbling_throw()
    cam = scene(1.7, 30.0, -45.0, path)
    cal = floor.calibrate(marks(cam, path, 0.0), cam.width, cam.height)
    z = path[:, 2]
    first = int(np.flatnonzero((z[1:-1] < z[:-2]) & (z[1:-1] < z[2:]))[0]) + 1  # the first landing
    uv = cam.project(path[: first - 3])
    got = floor.heights(cal.camera, t[: first - 3], uv[:, 0], uv[:, 1], REST)
    assert not np.any(np.isclose(got, REST)), "a flight is not on the floor"


def test_frames_the_floor_cannot_place_split_the_track_so_a_piece_holds_only_heights():
    status = np.ones(10, np.int8)
    segment = np.array([0, 0, 0, 0, 0, 0, 1, 1, 1, 1], np.int32)
    placed = np.array([1, 1, 0, 0, 1, 1, 1, 0, 1, 1], bool)
    st, seg = floor._unknown_split(status, segment, placed)
    assert seg.tolist() == [0, 0, -1, -1, 1, 1, 2, -1, 3, 3] and st.tolist() == [1, 1, 0, 0, 1, 1, 1, 0, 1, 1]


@pytest.mark.parametrize("late", [2, -2])
def test_a_contact_time_the_image_misjudges_by_two_frames_is_fitted_again_from_the_flight(late):
    """A hop between two contacts on the rest plane, its contacts' times given ``late`` frames off (the tracks on
    either side of a blurred bounce meet a frame or two away from it): the fit moves them back, and the hop's
    heights stay within half a centimetre RMS (held at the wrong times: 6 and 19 mm)."""
    fps, hop = 60.0, 0.5
    t = np.arange(int(hop * fps) + 1) / fps
    a, b = np.array([0.0, 0.0, REST]), np.array([0.8, 0.3, REST])
    path = a + (b - a) * (t / hop)[:, None] + np.column_stack([0 * t, 0 * t, 0.5 * G * t * (hop - t)])
    cam = scene(1.2, 20.0, 30.0, path)
    uv = cam.project(path)
    off = late / fps
    contacts = [(0.0 + off, a), (hop - off, b)]
    frames = np.arange(1, len(t) - 1)
    xyz = floor._joint(cam, t, uv[:, 0], uv[:, 1], [(0, 1, frames)], contacts, REST, REST)[0]
    assert np.sqrt(np.mean((xyz[:, 2] - path[frames, 2]) ** 2)) < 0.005


@pytest.mark.parametrize("late", [2, 1, -2])
def test_frames_split_at_a_misjudged_bounce_are_placed_by_the_fitted_contact_not_below_the_floor(late):
    """Two hops, the bounce between them seen ``late`` frames off, and the frames split between the hops at that
    time as the image gives it (``_contacts`` does): once the fit moves the contact back, the frames on the wrong
    side of it are at the contact, not on their hop's parabola extended past it (which ran 9 cm below the floor)."""
    fps, t1, t2 = 60.0, 0.5, 0.9
    t = np.arange(int(t2 * fps) + 1) / fps
    a, b, c = np.array([0.0, 0.0, REST]), np.array([0.8, 0.3, REST]), np.array([1.3, 0.5, REST])

    def hop(p, q, ta, tb, times):
        w = ((times - ta) / (tb - ta))[:, None]
        return (1 - w) * p + w * q + np.column_stack([0 * w[:, 0], 0 * w[:, 0], 0.5 * G * (times - ta) * (tb - times)])

    path = np.where((t <= t1)[:, None], hop(a, b, 0.0, t1, t), hop(b, c, t1, t2, t))
    cam = scene(1.2, 20.0, 30.0, path)
    uv = cam.project(path)
    seen = t1 + late / fps
    contacts = [(0.0, a), (seen, b), (t2, c)]
    flights = [(0, 1, np.flatnonzero((t > 0.0) & (t <= seen))), (1, 2, np.flatnonzero((t > seen) & (t < t2)))]
    out = floor._joint(cam, t, uv[:, 0], uv[:, 1], flights, contacts, REST, REST)
    err = np.concatenate([xyz[:, 2] - path[f, 2] for (_, _, f), xyz in zip(flights, out)])
    z = np.concatenate([xyz[:, 2] for xyz in out])
    assert z.min() > REST - 0.005, "no frame placed below the floor beside the bounce"
    assert np.sqrt(np.mean(err**2)) < 0.012


def test_the_apparent_size_holds_a_first_flight_that_a_low_camera_and_a_tracker_jump_leave_open(monkeypatch):
    """A camera 0.4 m over the floor, a 4-pixel tracker jump for three frames of the first fall, over 8 draws of the
    pixels' noise: with each frame's depth from its apparent size the first flight (no contact before it) comes
    closer on average, a little at the shipped spread (exact sizes: 17.9 -> 17.5 mm; the spread is loose because a
    video's blob is not exact) and more with the size trusted (spread 0.1: 14.3 mm); a size 10 % off with 5 % noise
    a frame, the clip's bias the fit finds, costs under 2.5 mm on average."""
    t, path = tumbling_throw(fps=30.0)
    cam = scene(0.4, 3.0, 20.0, path)
    cal = floor.calibrate(marks(cam, path, 1.0), cam.width, cam.height)
    depth = cam.depth_of(path)
    first = slice(0, 12)  # the throw's first flight

    def off(z: np.ndarray) -> float:
        return float(np.sqrt(np.nanmean((z - path[:, 2])[first] ** 2)))

    def mean_offs() -> tuple[float, float, float]:
        without, exact, biased = [], [], []
        for seed in range(8):
            rng = np.random.default_rng(100 + seed)
            uv = cam.project(path) + rng.normal(0.0, 0.5, (len(t), 2))
            uv[6:9, 1] += 4.0
            sized = 1.1 * depth * np.exp(rng.normal(0.0, 0.05, len(t)))
            without.append(off(floor.heights(cal.camera, t, uv[:, 0], uv[:, 1], REST)))
            exact.append(off(floor.centres(cal.camera, t, uv[:, 0], uv[:, 1], REST, depth)[0][:, 2]))
            biased.append(off(floor.centres(cal.camera, t, uv[:, 0], uv[:, 1], REST, sized)[0][:, 2]))
        return float(np.mean(without)), float(np.mean(exact)), float(np.mean(biased))

    without, exact, biased = mean_offs()
    assert exact < without
    assert biased < without + 0.0025, f"{biased} {without} {exact}"
    monkeypatch.setattr(floor, "SIZE_SD", 0.1)
    _, trusted, _ = mean_offs()
    assert trusted < 0.9 * without, "a size trusted more holds the first flight more"


def _track(cam, t: np.ndarray, uv: np.ndarray, diameter: np.ndarray) -> Trajectory:
    n = len(t)
    return Trajectory(t=t, u=uv[:, 0], v=uv[:, 1], status=np.ones(n, np.int8), segment=np.zeros(n, np.int32),
                      confidence=np.ones(n), diameter=diameter, fps=30.0, source="throw.mp4", width=cam.width,
                      height_px=cam.height)


def test_on_floor_reads_the_blobs_diameter_given_the_objects_size_and_ignores_diameters_it_cannot_use():
    t, path = tumbling_throw(fps=30.0)
    cam = scene(0.4, 3.0, 20.0, path)
    uv = cam.project(path)
    uv[6:9, 1] += 4.0  # a tracker's jump mid-fall
    size, f = 0.2, marks(cam, path, 0.0)
    plain, _ = floor.on_floor(_track(cam, t, uv, cam.focal * size / cam.depth_of(path)), f, REST)
    sized, _ = floor.on_floor(_track(cam, t, uv, cam.focal * size / cam.depth_of(path)), f, REST, size)

    def off(z: np.ndarray) -> float:
        return float(np.sqrt(np.nanmean((z - path[:, 2]) ** 2)))

    assert off(sized.z) < off(plain.z), "the blob's size brings the heights closer"
    for unusable in (np.nan, 0.0, np.inf):  # not measured, or nothing a depth can come from
        got, _ = floor.on_floor(_track(cam, t, uv, np.full(len(t), unusable)), f, REST, size)
        np.testing.assert_array_equal(got.z, plain.z)
    with pytest.raises(ConfigError, match="size"):
        floor.on_floor(_track(cam, t, uv, np.full(len(t), 30.0)), f, REST, 0.0)


def test_an_unreadable_floor_file_and_a_floor_that_cannot_fix_the_focal_length_are_said(tmp_path):
    """Bytes that are not text are one error naming the file; a camera square above the floor sees no perspective,
    so the marks cannot fix its focal length: the answer says the 60 degrees it took."""
    from study.see.camera import Camera

    f = tmp_path / "FLOOR.csv"
    f.write_bytes(b"\xff\xfe\x00u,v\x80\x81")
    with pytest.raises(DataError, match="FLOOR.csv: cannot be read .*write it as a plain CSV"):
        floor.read_floor(f)
    down = Camera((0.0, 0.0, 3.0), (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), 500.0, 640, 480)  # looks down -z
    marks_ = floor.seen(down, RECTANGLE[:6])
    assert len(marks_.points) == 6
    cal = floor.calibrate(marks_, 640, 480)
    assert cal.assumed_fov and "60° taken" in cal.note() and "the marks cannot fix the focal length" in cal.note()
    fov = 2 * math.degrees(math.atan(0.5 * 480 / cal.camera.focal))
    assert fov == pytest.approx(60.0), "the assumed field of view is the one the note gives"


def test_a_box_rocking_on_its_edge_between_flights_is_placed_on_its_ray_not_behind_it_on_the_floor():
    """A box lies still for 2 s but rocks onto an edge for 0.3 s in the middle, its centre 4 cm up: its ray meets the
    rest plane behind it, and the ground's near envelope keeps it where it is."""
    fps, n = 60.0, 120
    t = np.arange(n) / fps
    path = np.tile([0.3, 0.2, REST], (n, 1))
    rock = (t > 0.85) & (t < 1.15)
    path[rock, 2] += 0.04
    cam = scene(1.0, 20.0, 0.0, path)
    uv = cam.project(path)
    plane = floor._on_plane(cam, uv[:, 0], uv[:, 1], REST)
    near = floor._near_envelope(cam, t, plane, np.ones(n, bool))
    assert np.abs(plane[rock, 2] - path[rock, 2]).max() > 0.035, "the plane alone puts the rocking box on the floor"
    assert np.abs(near[:, 2] - path[:, 2]).max() < 0.005
    assert np.linalg.norm(near - path, axis=1).max() < 0.01


def test_a_box_sliding_away_to_rest_keeps_its_distance():
    """The envelope cuts short rises of the distance only: a box sliding away from the camera until friction stops
    it is left where it is."""
    fps, n = 60.0, 90
    t = np.arange(n) / fps
    slide = np.minimum(t, 1.0)
    path = np.column_stack([np.zeros(n), -0.5 + 1.2 * slide - 0.6 * slide**2, np.full(n, REST)])  # 0.6 m, 1.2 m/s
    cam = scene(1.0, 20.0, 0.0, path)
    uv = cam.project(path)
    plane = floor._on_plane(cam, uv[:, 0], uv[:, 1], REST)
    near = floor._near_envelope(cam, t, plane, np.ones(n, bool))
    np.testing.assert_allclose(near, path, atol=1e-6)


@pytest.mark.parametrize("kind, size", [("sphere", (0.067,)), ("box", (0.2, 0.2, 0.2)), ("box", (0.1, 0.2, 0.4)),
                                        ("cylinder", (0.1, 0.3))])
def test_the_contact_height_is_the_support_functions_mean_over_random_orientations(kind, size):
    """Averaged over directions u, a body touching the floor has its centre as high as its support function h(u): a
    box's half-edges times |u|, summed; a cylinder's half-length times |u_z| plus its radius times the rest."""
    n = 200_000  # a Fibonacci sphere: directions spread evenly
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z**2)
    phi = math.pi * (1 + math.sqrt(5)) * i
    u = np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    if kind == "sphere":
        h = np.full(n, size[0] / 2)
    elif kind == "box":
        h = np.abs(u) @ (np.array(size) / 2)
    else:
        h = size[1] / 2 * np.abs(u[:, 2]) + size[0] / 2 * np.sqrt(1 - u[:, 2] ** 2)
    shape = ObjectShape(kind, size)
    assert floor.contact_height(shape) == pytest.approx(h.mean(), rel=1e-4)
    assert shape.rest_height() <= floor.contact_height(shape) <= h.max() + 1e-12


def test_a_contact_height_below_the_rest_height_is_refused_by_name():
    """An object touches the floor with its centre at least as high as when it rests on it."""
    t, path = tumbling_throw()
    cam = scene(1.0, 20.0, 0.0, path)
    uv = cam.project(path)
    traj = _track(cam, t, uv, np.full(len(t), 20.0))
    with pytest.raises(ConfigError, match="contact height"):
        floor.on_floor(traj, marks(cam, path, 0.0), REST, contact_height=0.5 * REST)


def test_floor_limits_script_raises_only_a_presets_s_and_v_floor_and_swaps_in_the_renderers_pixels():
    limits = scripts_toys.script("scripts/floor_limits.py")
    for colour in ("orange", "red", "green", "blue"):
        (h_lo, s_lo, v_lo), (h_hi, s_hi, v_hi) = COLORS[colour]
        lo, hi = limits.lit_config(colour).bounds()
        assert list(lo) == [h_lo, *limits.LIT[colour]] and list(hi) == [h_hi, s_hi, v_hi], colour
        assert lo[1] >= s_lo and lo[2] > v_lo, f"{colour}: the lit tracker drops more than the preset"
    t = np.arange(6) / 30
    frame = types.SimpleNamespace(width=640, height=360)
    px = _track(frame, t, np.column_stack([np.arange(6.0), 10 + np.arange(6.0)]), np.full(6, 20.0))
    swapped = limits.rendered(px, {"u": np.array([100.0, 101.0, 102.0, 103.0]), "v": np.array([50.0, 51, 52, 53])})
    np.testing.assert_array_equal(swapped.u, [100, 101, 102, 103, 4, 5])  # frames past the truth's end kept
    np.testing.assert_array_equal(swapped.v, [50, 51, 52, 53, 14, 15])
    np.testing.assert_array_equal(swapped.diameter, px.diameter)  # the blob sizes stay the tracker's
    e = [np.array([0.003, -0.004]), np.array([0.0])]  # medians -0.0005 and 0, removed per clip
    assert limits.centred_mm(e) == pytest.approx(1000 * math.sqrt(2 * 0.0035**2 / 3))


def test_a_flights_heights_follow_its_own_pixels_at_the_fitted_depth_not_the_drag_free_arc():
    """The joint fit gives each flight frame's depth, and the frame's own pixel gives its point: a centre that
    wobbles about its arc (a tumbling box's centroid) is followed, where the arc's own
    points would smooth it away."""
    t, path = tumbling_throw()
    cam = scene(1.0, 5.0, 0.0, path)
    wobbly = path.copy()
    flying = path[:, 2] > REST + 1e-6
    wobbly[flying, 2] += 0.01 * np.sin(2 * np.pi * 2 * t[flying])  # 10 mm at 2 Hz: no parabola holds it
    uv = cam.project(wobbly)
    xyz, ground = floor.centres(cam, t, uv[:, 0], uv[:, 1], REST)
    flight = np.isfinite(xyz).all(axis=1) & ~ground
    assert flight.sum() > 60
    np.testing.assert_allclose(cam.project(xyz[flight]), uv[flight], atol=1e-6)
    rms = np.sqrt(np.mean((xyz[flight, 2] - wobbly[flight, 2]) ** 2))
    assert rms < 0.004, f"{1000 * rms:.1f} mm off the wobbling centre"
