"""The chapter *What the network sees* (study.chapters.cues): each step on toy data whose only cue is known, the
result assembled from fake parts, and the whole computation on run records written into a fresh cache."""

from __future__ import annotations

import dataclasses
import json
from types import SimpleNamespace

import numpy as np
import pytest
from fake_runs import cache_records

from study.book import results
from study.book.publish import glued
from study.chapters import cues
from study.learn.config import TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy
from study.methods import calibration, windows
from study.methods.tracker import Decomposition, TrackerError
from study.methods.tracker_model import TrackerFit
from study.runs import Runner, paper, records
from study.runs.runtable import Run, Runs
from study.simulate import data, observe
from study.simulate.observe import TrackerNoise

BEFORE = Decomposition(15.0, 7.3, 14.8, 0.78, 17.8, 5.4, 0.274, 0.59, 21.7, 14.8, 92.0, 0.0, 2400, 24)
AFTER = Decomposition(1.6, 1.2, 3.8, 0.52, 4.9, 2.0, 0.108, 0.156, 4.3, 3.8, 92.0, 0.0, 2400, 24)
MODEL = TrackerNoise(flight=0.02, contact=0.008, offset=0.006, rho=0.84)
FIT = TrackerFit(MODEL, drop=0.01, intervals={k: Interval(
    getattr(MODEL, k), 0.9 * getattr(MODEL, k), 1.1 * getattr(MODEL, k), "bootstrap over 40 videos")
    for k in ("offset", "rho", "flight", "contact")}, n_videos=40, n_frames=3000, n_contact=1200, step_sd=0.0095,
    pooled_sd=0.014, bias=0.002, lag1=0.8, fitted_on="40 development renders (render seed 2000)")
"""A fitted error model as ``calibration.tracker_fit`` gives it."""


def drag_only(n: int, seed: int, fps: float = 30.0, frames: int = 60) -> data.Split:
    """Falls from 1.5-2 m that stop dead at 0.1 m; light objects fall at 9.3 m/s^2, heavy at 9.8: drag is the
    only difference. (n, frames, 3) metres, labels alternate light, heavy."""
    rng = np.random.default_rng(seed)
    y = (np.arange(n) % 2).astype(np.int64)
    g = np.where(y == 1, 9.8, 9.3)
    t = np.arange(frames) / fps
    z = rng.uniform(1.5, 2.0, n)[:, None] + rng.uniform(0, 1, n)[:, None] * t - g[:, None] / 2 * t**2
    x = np.zeros((n, frames, 3))
    x[..., 2] = np.maximum(z, 0.1)
    return data.Split(x.astype(np.float32), y)


def test_window_cues_finds_the_drag_cue_before_any_landing():
    ds = data.Dataset(train=drag_only(200, 0), test=drag_only(200, 1), fps=30.0)
    short, long = windows.window_cues(ds, (0.3, 2.0), contact_height=0.15)
    assert short["length"] == 0.3 and short["landed"] == 0.0  # nothing reaches the ground in 9 frames
    assert long["landed"] == 1.0
    assert short["drag"].value > 0.9 and short["drag"].lo <= short["drag"].value <= short["drag"].hi
    assert short["other_feature"] != "fall_acceleration"
    assert short["other"].value < short["drag"].value


def with_params(split: data.Split, **params: np.ndarray) -> data.Split:
    return data.Split(split.x, split.y, params)


def test_the_fitted_ceiling_reads_the_true_parameters():
    """A class that the restitution alone separates gives a ceiling near 100 %; telling the classifier a mass
    that the classes share adds nothing, one they do not share makes it perfect."""
    rng = np.random.default_rng(0)

    def split(n: int) -> data.Split:
        y = (np.arange(n) % 2).astype(np.int64)
        e = np.where(y == 0, rng.uniform(0.6, 0.8, n), rng.uniform(0.2, 0.4, n))
        shared = rng.uniform(0.3, 0.7, n)
        return with_params(data.Split(np.zeros((n, 2, 3), np.float32), y), restitution=e, friction=shared,
                           mass=np.where(y == 0, 0.2, 5.0) * rng.uniform(0.9, 1.1, n))

    ds = data.Dataset(train=split(400), test=split(400), fps=30.0)
    iv = cues.ceiling(ds)
    assert iv.value > 0.97 and iv.lo <= iv.value <= iv.hi
    assert cues.ceiling(ds, with_mass=True).value == 1.0
    noisy = data.Dataset(train=split(400), test=split(400), fps=30.0)
    for s in (noisy.train, noisy.test):
        s.params["restitution"] = rng.permutation(s.params["restitution"])  # no longer tied to the class
    assert cues.ceiling(noisy).hi < 0.6


def test_mixed_shapes_pool_the_training_splits_and_name_their_parts():
    a = data.Dataset(train=drag_only(10, 0), test=drag_only(6, 1), fps=30.0, meta={"key": "a"})
    b = data.Dataset(train=drag_only(8, 2), test=drag_only(6, 3), fps=30.0, meta={"key": "b"})
    mixed = cues.mixed_shapes({"cube": a, "ball": b}, names=("cube", "ball"))
    assert len(mixed.train) == 18 and mixed.test is a.test and mixed.fps == 30.0
    np.testing.assert_array_equal(mixed.train.x[10:], b.train.x)
    other = cues.mixed_shapes({"cube": a, "ball": b}, names=("ball", "cube"))
    assert mixed.key and other.key and mixed.key != other.key, "the key names its parts, in order"


# --- The chapter's computation, step by step -----------------------------------------------------


def test_the_drag_cue_is_fitted_on_train_and_blurred_by_noise():
    ds = data.Dataset(train=drag_only(200, 0), test=drag_only(200, 1), fps=30.0)
    drag = cues.drag_cue(ds, 12, contact_height=0.15, noise_mm=[0, 5, 200])
    assert list(drag.noisy) == [5, 200], "no noise is the exact rule, not a noisy one"
    assert drag.exact.value > 0.9 and drag.rule["direction"] == "<="  # heavy: the steeper (more negative) fall
    assert drag.median["light"] == pytest.approx(-9.3, abs=0.05) and drag.median["heavy"] == pytest.approx(-9.8, abs=0.05)
    assert drag.noisy[200].value < drag.noisy[5].value <= drag.exact.value + 1e-9
    assert drag.fall.shape == (200,) and (drag.y == ds.test.y).all()


class Threshold:
    """A fake model: heavy where the mean height of the input is below ``cut`` metres."""

    def __init__(self, cut: float):
        self.cut = cut

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        heavy = (np.asarray(x)[..., 2].mean(axis=1) < self.cut).astype(float)
        return np.column_stack([1 - heavy, heavy])


def two_heights(n: int = 40, frames: int = 30) -> tuple[np.ndarray, np.ndarray]:
    """Light throws resting at 0.6 m, heavy at 0.3 m: (n, frames, 3) metres and labels."""
    y = (np.arange(n) % 2).astype(np.int64)
    x = np.zeros((n, frames, 3))
    x[..., 2] = np.where(y == 1, 0.3, 0.6)[:, None]
    return x, y


def test_robustness_scores_each_group_at_each_point_and_skips_rates_it_cannot_film():
    x, y = two_heights()
    O = observe.Observation
    sweeps = {"scale": cues.Sweep("height-scale factor", [1.0, 4.0], lambda v: O(height_factor=v)),
              "fps": cues.Sweep("camera frame rate, fps", [15, 60], lambda v: O(camera_fps=float(v)))}
    models = {"exact": [Threshold(0.45)], "random": [Threshold(0.45), Threshold(10.0)]}
    points = cues.robustness(models, x, y, 30.0, 20, sweeps)
    assert [(p.sweep, p.value, p.group) for p in points] == [
        ("scale", 1.0, "exact"), ("scale", 1.0, "random"), ("scale", 4.0, "exact"), ("scale", 4.0, "random"),
        ("fps", 15, "exact"), ("fps", 15, "random")], "60 fps needs the high-rate throws, which were not given"
    at = {(p.sweep, p.value, p.group): p.interval.value for p in points}
    assert at["scale", 1.0, "exact"] == 1.0 and at["scale", 1.0, "random"] == 0.75  # one of its two calls all heavy
    assert at["scale", 4.0, "exact"] == 0.5, "heights four times too high: every throw looks light"


def test_accuracy_by_parameter_and_inside_the_overlap():
    n = 16
    y = (np.arange(n) % 2).astype(np.int64)
    e = np.where(y == 0, np.linspace(0.4, 0.9, n), np.linspace(0.1, 0.6, n))
    split = data.Split(np.zeros((n, 2, 3), np.float32), y, {"restitution": e})
    correct = np.stack([(e < 0.4) | (e > 0.5)] * 2)  # both seeds wrong inside [0.4, 0.5]
    bins = cues.by_parameter(correct, split, "restitution", bins=2)
    assert [(b.label, b.index, b.n) for b in bins] == [(0, 0, 4), (0, 1, 4), (1, 0, 4), (1, 1, 4)]
    assert bins[1].accuracy == 1.0 and bins[1].centre > bins[0].centre
    prior = SimpleNamespace(light=SimpleNamespace(restitution=(0.4, 0.9)), heavy=SimpleNamespace(restitution=(0.1, 0.5)))
    ov = cues.overlap(correct, e, prior)
    assert (ov.lo, ov.hi) == (0.4, 0.5) and ov.inside.value == 0.0 and ov.outside.value == 1.0


def test_shape_keys_are_the_results_file_names():
    assert [cues.shape_key(n) for n in cues.SHAPES] == ["20_cm_cube", "10_cm_cube", "30_cm_cube",
                                                        "flat_box_30_x_30_x_10_cm", "ball", "cylinder"]


# --- The chapter's result from its parts ---------------------------------------------------------


def runs_right(dims: str, rights: list[np.ndarray]) -> Runs:
    """Runs of ``dims``, one per seed, right on the test throws ``rights[s]`` (bool)."""
    return Runs(Run(TrainConfig(dims=dims, seed=s), 0.7, 0.4, 3, 1, 1.0, False, accuracy=float(r.mean()),
                    correct=np.asarray(r, bool)) for s, r in enumerate(rights))


def rule(feature: str, train: float, right: np.ndarray) -> dict:
    return {"feature": feature, "threshold": 0.0, "direction": ">", "train_accuracy": train,
            "test_accuracy": float(right.mean()), "correct": right, "interval": bootstrap_accuracy(right)}


N = 80
RNG = np.random.default_rng(0)


def right(share: float) -> np.ndarray:
    """(N,) bool, right on about ``share`` of the throws."""
    return RNG.random(N) < share


def parts(network_b: float, rule_b: float = 0.6) -> dict:
    """The chapter's parts, the network without air right on ``network_b`` of the throws, the best rule on
    ``rule_b``; the rule that is best on the test split is not the one training picks."""
    a = runs_right("z", [right(0.8)] * 2) + runs_right("xyz", [right(0.85)] * 2)
    b = runs_right("z", [right(network_b)] * 2) + runs_right("xyz", [right(network_b)] * 2)
    rules = {k: [rule("bounces", 0.7, right(rule_b)), rule("fall_acceleration", 0.6, right(0.95 if k == "a" else 0.5)),
                 rule("distance", 0.65, right(0.99))] for k in ("a", "b", "c")}
    correct = {("a", "xyz"): a.where(dims="xyz").correct(), ("a", "z"): a.where(dims="z").correct(),
               ("b", "xyz"): b.where(dims="xyz").correct(), ("b", "z"): b.where(dims="z").correct(),
               ("c", "z"): np.stack([right(0.6)] * 2), ("d", "z"): np.stack([right(0.7)] * 2)}
    cond = cues.Conditions(a, b, [], [], correct, rules)
    ds = data.Dataset(train=drag_only(60, 0), test=drag_only(60, 1), fps=30.0)
    sweeps = {"drop": cues.Sweep("share of frames lost", [0.0, 0.1], lambda v: observe.Observation(drop=v))}
    points = [cues.Point("drop", v, g, bootstrap_accuracy(right(0.7))) for v in (0.0, 0.1) for g in cues.GROUPS]
    shapes = [cues.ShapeScore(n, bootstrap_accuracy(right(0.6)), bootstrap_accuracy(right(0.7))) for n in cues.SHAPES]
    return dict(drag=cues.drag_cue(ds, 12, 0.15, [0, 2, 10]), tracker=TrackerError(1.1, 0.015, 0.02, 120, 0.0138),
                cond=cond, fitted=(bootstrap_accuracy(right(0.8)), bootstrap_accuracy(right(1.0))), exact=0.86,
                sweeps=sweeps, points=points, by={}, errors=cues.Overlap(0.35, 0.5, bootstrap_accuracy(right(0.5)),
                                                                         bootstrap_accuracy(right(0.9))),
                shapes=shapes, n_videos=4, length_frames=12)


@pytest.fixture(scope="module")
def beats():
    return cues.assemble(**parts(network_b=0.95))


def test_every_number_keeps_its_name_and_reads_back_from_the_results_file(beats, tmp_path):
    names = [name for name, _ in beats.numbers.entries()]
    assert {"cues.drag_rule.exact", "cues.drag_rule.noise_2mm", "cues.drag_rule.noise_10mm", "cues.tracker.noise_m",
            "cues.tracker.drop", "cues.condition_a.xyz", "cues.condition_c.z", "cues.condition_d.z", "cues.best_rule_b",
            "cues.drag_rule_c", "cues.ceiling.restitution_friction", "cues.ceiling.with_mass", "cues.ceiling.exact",
            "cues.network_minus_rule_b.xyz", "cues.network_minus_rule_b.z", "cues.claim_without_drag",
            "cues.robustness.drop.0.exact", "cues.robustness.drop.0.1.random", "cues.errors.overlap_z",
            "cues.errors.outside_z", "cues.shape.20_cm_cube.cube_model", "cues.shape.ball.mixed_model"} <= set(names)
    assert len(names) == len(set(names)) == 3 + 2 + 6 + 3 + 3 + 3 + 2 + 1 + 4 + 2 + 12
    assert "cues.condition_c.xyz" not in names, "one camera gives a height: (c) and (d) are Z only"
    assert beats.numbers.tracker.noise_m.unit == "m" and beats.numbers.ceiling.exact.exact
    f = tmp_path / "results.json"
    f.write_text(results.dumps(beats.numbers.entries()))
    assert cues.Numbers.read(results.load(f)) == beats.numbers


def test_the_best_rule_is_chosen_on_training_accuracy_never_on_the_test_split(beats):
    assert beats.conditions.best_rule("b")["feature"] == "bounces", "distance is better on test, worse on train"
    assert "(bounces)" in beats.numbers.best_rule["b"].what
    assert beats.numbers.drag_rules["a"].value == beats.conditions.drag_rule("a")["interval"].value


def test_the_verdicts_and_sentences_follow_from_the_numbers(beats):
    n = beats.numbers
    assert all(m.verdict == "reproduced" and m.signed for m in n.network_minus_rule_b.values())
    assert n.claim_without_drag.verdict == "reproduced"
    assert "the networks still beat the best one-feature rule" in beats.cue_verdict
    loses = cues.assemble(**parts(network_b=0.3))
    assert {m.verdict for m in loses.numbers.network_minus_rule_b.values()} == {"differs"}
    assert loses.numbers.claim_without_drag.verdict == "differs"
    assert "does not beat the best one-feature rule for X, Y, Z (differs) and Z only (differs)" in loses.cue_verdict
    assert "does not rest on drag" not in loses.cue_verdict, "(b) lies below (a): the drag cue carried part of it"
    acc = beats.conditions.accuracy
    assert f"{100 * (acc['c', 'z'].value - acc['a', 'z'].value):+.1f} points" in beats.obs_verdict


def test_the_tables_and_the_chapter_s_words(beats):
    rows = beats.cue_table.rows
    assert [r["condition"] for r in rows] == list(cues.CONDITIONS.values())
    assert rows[3]["drag"] == rows[3]["best"] == rows[3]["xyz"] == "—" and rows[2]["xyz"] == "—"
    assert rows[1]["best"].endswith("(bounces)")
    assert [r["noise"] for r in beats.drag_noise_table.rows] == ["2 mm", "10 mm"]
    assert [r["seen"] for r in beats.shape_table.rows] == ["yes", "no", "no", "yes", "yes", "yes"]
    assert (beats.noise_mm, beats.noise_px, beats.mm_per_px, beats.n_cal_frames) == ("15.0", "1.10", "13.8", 120)
    assert beats.overlap_range == "0.35–0.5" and beats.ceil_gap == f"{100 * (0.86 - beats.numbers.ceiling.restitution_friction.value):+.1f}"
    assert beats.n_sweeps == 1 and beats.length_frames == 12


# --- The whole computation, every run read from fake records -------------------------------------


def _score(c: TrainConfig) -> float:
    """Test accuracy of a fake run: X, Y, Z above Z; a run without air below one with; random observations lower."""
    return 0.6 + 0.2 * (c.dims == "xyz") - 0.1 * (c.observe == "randomised")


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    runner = Runner.open("smoke", data_dir=tmp_path_factory.mktemp("data"), workers=1)
    p = runner.preset

    def would_train(*args, **kwargs):
        raise AssertionError(f"the chapter trained a run instead of reading its record: {args[1]}")

    mp.setattr(records, "run", would_train)
    mp.setattr(calibration, "rendered", lambda runner: (["rendered.mp4"] * 3, None))
    mp.setattr(calibration, "tracker_error", lambda runner: TrackerError(1.0, 0.014, 0.05, 90, 0.014))
    mp.setattr(calibration, "tracker_fit", lambda runner: FIT)
    mp.setattr(calibration, "decomposition", lambda runner: {"before": BEFORE, "after": AFTER})
    mp.setattr(Runner, "models", lambda self, cfg, seeds, **changes: [Threshold(0.3 + 0.1 * s) for s in seeds])
    toy = {name: dataclasses.replace(runner.dataset, meta={**runner.dataset.meta, "key": f"shape-{i}"})
           for i, name in enumerate(cues.SHAPES)}  # the smoke throws under six names: no new simulation
    mp.setattr(cues, "shape_sets", lambda *args, **kwargs: toy)
    cache_records(runner, paper.grid_configs(p, "peephole"), test=False)
    cfg = runner.table1_config()
    for r, cfgs, test in cues.condition_configs(runner, cfg):
        cache_records(r, cfgs, _score, test=test, val_score=lambda c: 0.7)  # Table 1's grid point keeps its score
    mixed = runner.on(cues.saved(runner, cues.mixed_shapes(toy), "mixed"))
    cache_records(mixed, paper.seed_configs(cfg, p.grid_seeds, ("z",)))
    sweeps = {"fps": cues.Sweep("camera frame rate, fps", [15, 120], lambda v: observe.Observation(camera_fps=v))}
    try:
        yield runner, cues.compute(runner, [0, 5], sweeps)
    finally:
        mp.undo()


def test_compute_reads_every_run_from_its_record_and_scores_the_models_as_observed(whole):
    runner, result = whole
    n = result.numbers
    assert n.conditions["a"]["xyz"].value == pytest.approx(0.8, abs=1 / 16)
    assert n.conditions["a"]["z"].value == pytest.approx(0.6, abs=1 / 16) and set(n.conditions["c"]) == {"z"}
    assert "2 seeds" in n.conditions["b"]["z"].method, "the grid's seeds"
    assert list(n.drag_rule.noise) == ["5"] and n.tracker.noise_m.value == 0.014
    assert list(n.robustness["fps"].points) == ["15", "120"], "120 fps filmed from the high-rate throws"
    assert list(n.shape) == [cues.shape_key(s) for s in cues.SHAPES]
    assert result.n_videos == 3 and result.length_frames == runner.table1_config().n_frames(runner.fps)
    assert len(result.by_parameter) == 6 and all(result.by_parameter.values())
    assert result.drag.fall.shape == (len(runner.dataset.test),)


def test_the_fitted_error_model_is_reported_and_is_what_observed_runs_draw(whole):
    runner, result = whole
    m = result.numbers.tracker_model
    assert (m.offset.value, m.rho.value, m.flight.value, m.contact.value) == (0.006, 0.84, 0.02, 0.008)
    assert m.offset.unit == "m" and m.videos.value == 40 and "development renders" in m.flight.what
    assert m.white_step_sd.value == pytest.approx(np.sqrt(2) * 0.014) and m.step_sd.value == 0.0095
    assert result.model_description == MODEL.describe() and result.white_ratio == "2.1"
    assert (result.tracker_step_mm, result.tracker_pooled_mm, result.model_band_mm) == ("9.5", "14.0", "5")
    glue = dict(glued(result))  # no two glued under one name
    assert glue["model_description"] == MODEL.describe() and glue["tracker_model.offset"].endswith("]")
    names = {name for name, _ in result.numbers.entries()}
    assert {f"cues.tracker_model.{k}" for k in ("offset", "rho", "flight", "contact", "step_sd", "drop")} <= names
    robust = calibration.randomised_config(runner, runner.table1_config())
    assert (robust.observe_rho, robust.observe_offset, robust.observe_noise) == (0.84, 0.006, 0.02)
    assert robust.observe_drop == 0.01, "validated as the fitted tracker observes"


def test_the_tracker_before_and_after_is_reported_in_si_units_and_tabled(whole):
    _, result = whole
    n = result.numbers.tracker.decomposed
    assert set(n) == {"before", "after"}
    assert n["before"].bias.value == pytest.approx(0.015) and n["after"].bias.value == pytest.approx(0.0016)
    assert n["after"].rho.unit == "correlation" and n["after"].velocity.value == pytest.approx(0.108)
    assert "V ≥ 80" in n["before"].bias.what
    names = {name for name, _ in result.numbers.entries()}
    assert {"cues.tracker.before.bias", "cues.tracker.after.height_rms_median"} <= names
    table = result.tracker_table.markdown()
    assert "15.0" in table and "1.6" in table and "0.108" in table


def test_the_tracker_error_reads_back_its_cache_file_and_gives_the_calibrated_observation():
    err = TrackerError(noise_px=1.08, noise_m=0.01495, drop=0.02, n_frames=120, metres_per_pixel=0.0138)
    assert TrackerError.from_json(json.loads(json.dumps(err.to_json()))) == err
    assert err.observation() == observe.Observation(noise=0.01495, drop=0.02)
    old = {"noise_px": 1.08, "noise_m": 0.01495, "drop": 0.0, "n_frames": 120, "metres_per_pixel": 0.0138}
    assert TrackerError.from_json(old).drop == 0.0, "the calibration files of earlier builds hold the same fields"
