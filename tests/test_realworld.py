"""The real-world pipeline: manifests, a rendered set with known classes, classification against the model contract."""

from __future__ import annotations

import os

import numpy as np
import pytest

from study.experiments import realworld
from study.core.errors import ConfigError, DataError
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
    assert [r["file"] for r in rows] == [v.path.name for v in rendered_set]
    for r in rows:
        assert r["error"] == "" and 0.9 <= r["found"] <= 1.0 and r["p_light"] + r["p_heavy"] == pytest.approx(1.0)
    acc = realworld.per_class_interval(rows)
    assert set(acc) == {"light", "heavy"}
    for c, iv in acc.items():
        k = sum(r["correct"] for r in rows if r["label"] == c)
        assert iv.value == k / 1 and iv.lo <= iv.value <= iv.hi and "Wilson" in iv.method
    err = realworld.tracking_error(rendered_set)
    assert err["found"] >= 0.9 and err["mean_px"] < 3.0


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


def test_untrackable_video_is_a_row_not_a_crash(tmp_path):
    bad = tmp_path / "bad.mp4"
    bad.write_text("not a video")
    rows = realworld.classify(HeightRangeModel(), [realworld.Video(bad, "light")], progress=False)
    assert rows[0]["error"] and "bad.mp4" in rows[0]["error"]
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
