"""Synthesis: the batched rollout against the plain loop, determinism, caching, and bad configs."""

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from study.core.errors import ConfigError, DataError
from study.simulate import data, synth


@pytest.fixture(scope="module")
def params(smoke_cfg):
    p = synth.sample_split(smoke_cfg, 3, "train")
    keep = [0, 1, 8, 9]  # two light, two heavy
    return {k: v[keep] for k, v in p.items()}


@pytest.mark.parametrize("threads", [1, 2])
def test_rollout_is_bitwise_equal_to_the_plain_step_loop(smoke_cfg, params, threads):
    fast = synth.simulate(smoke_cfg, params, threads=threads, chunk=3, progress=False)
    plain = synth.simulate_reference(smoke_cfg, params)
    assert fast.shape == (4, smoke_cfg.n_frames, 3)
    assert fast.tobytes() == plain.tobytes()


def test_same_config_and_seed_give_identical_datasets(smoke_cfg):
    a = synth.generate(smoke_cfg, seed=5, progress=False)
    b = synth.generate(smoke_cfg, seed=5, progress=False)
    for name in data.SPLITS:
        assert a.split(name).x.tobytes() == b.split(name).x.tobytes()
    c = synth.generate(smoke_cfg, seed=6, progress=False)
    assert a.train.x.tobytes() != c.train.x.tobytes()


def test_dataset_layout(smoke_dataset, smoke_cfg):
    ds = smoke_dataset
    n = smoke_cfg.n_train
    assert ds.train.x.shape == (2 * n, smoke_cfg.n_frames, 3) and ds.train.x.dtype == np.float32
    assert list(ds.train.y) == [0] * n + [1] * n
    assert ds.fps == 30.0 and ds.key and ds.path.exists()
    # the launch state is frame 0, and every object ends on the ground
    assert np.allclose(ds.train.x[:, 0], ds.train.params["qpos0"][:, :3])
    assert np.all(ds.train.x[:, :, 2] > 0.05)


def test_train_and_test_use_disjoint_random_streams(smoke_cfg):
    tr = synth.sample_split(smoke_cfg, 0, "train")
    te = synth.sample_split(smoke_cfg, 0, "test")
    assert not np.intersect1d(tr["mass"], te["mass"]).size
    bigger = synth.sample_split(smoke_cfg.replace(n_test=20), 0, "train")
    assert np.array_equal(bigger["mass"], tr["mass"])  # n_test does not move train


def test_class_priors_are_respected(smoke_cfg):
    p = synth.sample_split(smoke_cfg.replace(n_train=200), 0, "train")
    for label, name in enumerate(("light", "heavy")):
        prior = smoke_cfg.prior(name)
        sel = p["label"] == label
        for field in ("mass", "restitution", "friction"):
            lo, hi = getattr(prior, field)
            assert np.all((p[field][sel] >= lo) & (p[field][sel] <= hi))


def test_cached_dataset_is_reused_and_a_corrupt_one_replaced(tmp_path, smoke_cfg):
    cfg = smoke_cfg.replace(n_train=2, n_test=2, duration=1.0)
    first = synth.dataset(cfg, data_dir=tmp_path, progress=False)
    mtime = first.path.stat().st_mtime_ns
    again = synth.dataset(cfg, data_dir=tmp_path, progress=False)
    assert again.path.stat().st_mtime_ns == mtime
    first.path.write_bytes(first.path.read_bytes()[:100])
    healed = synth.dataset(cfg, data_dir=tmp_path, progress=False)
    assert healed.train.x.tobytes() == first.train.x.tobytes()


def test_an_interrupted_save_leaves_nothing(tmp_path, smoke_dataset, monkeypatch):
    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(np, "savez", boom)
    with pytest.raises(KeyboardInterrupt):
        data.save(smoke_dataset, tmp_path / "d.npz")
    assert list(tmp_path.iterdir()) == []


def test_load_rejects_a_header_whose_config_does_not_match_its_key(tmp_path, smoke_dataset):
    meta = dict(smoke_dataset.meta, seed=smoke_dataset.meta["seed"] + 1)
    path = data.save(dataclasses.replace(smoke_dataset, meta=meta), tmp_path / "d.npz")
    with pytest.raises(DataError, match="do not match its key"):
        synth.load(path)


def test_a_file_from_before_sleeping_existed_loads_as_awake(tmp_path, smoke_dataset):
    """Headers written before SynthConfig.sleep_tolerance lack the field: such a file still loads, as sleep 0."""
    from study.core import cache

    meta = dict(smoke_dataset.meta)
    old = {k: v for k, v in meta["config"].items() if k != "sleep_tolerance"}
    meta |= {"config": old, "key": cache.key({"config": old, "seed": meta["seed"], **meta["versions"]})}
    path = data.save(dataclasses.replace(smoke_dataset, meta=meta), tmp_path / "old.npz")
    assert synth.SynthConfig.from_dict(synth.load(path).meta["config"]).sleep_tolerance == 0.0


@pytest.mark.parametrize(
    "change, field",
    [
        (dict(light=synth.ClassPrior((-1.0, 0.5), (0.5, 0.8), (0.3, 0.7))), "light.mass"),
        (dict(heavy=synth.ClassPrior((3.0, 25.0), (0.1, 1.2), (0.3, 0.7))), "heavy.restitution"),
        (dict(heavy=synth.ClassPrior((3.0, 25.0), (-0.1, 0.5), (0.3, 0.7))), "heavy.restitution"),
        (dict(duration=0.0), "duration"),
        (dict(fps=0.0), "fps"),
        (dict(n_train=0), "n_train"),
        (dict(timestep=1 / 1000), "timestep"),
        (dict(stiffness=1e6), "stiffness"),
        (dict(sleep_tolerance=-1e-3), "sleep_tolerance"),
        (dict(sleep_tolerance=0.1), "sleep_tolerance"),
        (dict(sleep_tolerance=0.02), "sleep_tolerance"),  # sleeps at the apex of a throw at this timestep
        (dict(launch=synth.LaunchPrior(height=(0.05, 1.0))), "height"),
    ],
)
def test_bad_config_names_the_field(smoke_cfg, change, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        smoke_cfg.replace(**change)


def test_unknown_preset_and_class(smoke_cfg):
    with pytest.raises(ConfigError, match="preset = .huge. is unknown"):
        synth.SynthConfig.preset("huge")
    with pytest.raises(ConfigError, match="unknown class"):
        smoke_cfg.prior("medium")


def test_restitution_outside_the_calibration_is_refused(smoke_cfg):
    cfg = smoke_cfg.replace(heavy=synth.ClassPrior((3.0, 25.0), (0.01, 0.5), (0.4, 0.7)))
    with pytest.raises(ConfigError, match="calibrated range"):
        synth.generate(cfg, progress=False)


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "study", *args], capture_output=True, text=True, cwd=cwd)


@pytest.mark.slow
def test_cli_synth_smoke_writes_the_dataset_and_prints_its_path(tmp_path):
    out = tmp_path / "smoke.npz"
    r = run_cli("synth", "--preset", "smoke", "--seed", "1", "--out", str(out), "--no-progress")
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == str(out)
    ds = synth.load(out)
    assert ds.meta["seed"] == 1 and len(ds.train) == 16


def test_cli_synth_bad_input_is_one_line_and_exit_2(tmp_path):
    r = run_cli("synth", "--preset", "smoke", "--seed", "-3", "--out", str(tmp_path / "x.npz"))
    assert r.returncode == 2
    assert r.stderr.strip().count("\n") == 0 and "seed" in r.stderr
    assert not (tmp_path / "x.npz").exists()


def test_cli_help_explains_every_option():
    r = run_cli("synth", "--help")
    assert r.returncode == 0
    for option in ("--preset", "--seed", "--out", "--data-dir", "--threads"):
        assert option in r.stdout
