"""The data chapter's computation (study.chapters.data): its tables, its Figure 3 verdict, its choice of rule,
and the counts it glues, on arrays made here and on the smoke preset's tiny data set (the physics itself is
tested in test_physics.py)."""

from __future__ import annotations

import numpy as np
import pytest

from study.book import publish, results
from study.chapters import data
from study.simulate import measure, synth

OLD_GLUE = ("n_train n_test n_total duration fps n_frames dt_ms steps_per_frame stiffness contact_ms resolution "
            "edge_cm prior_table fig3_bounces fig3_rest stats_table min_rise_cm min_rise_frames min_rise_ms rock_cm "
            "best_rule best_rule_acc bounce_rule_acc best_rule_wrong n_test_throws rules_table flight_err "
            "flight_err_naive_mm conv_max drop_err pen_bound_mm pen_max_mm v_max rest_speed_mm n_still n_traces "
            "fl_max_rise fr_max_rise fr_n_rise fr_n fr_by_class rest_pct rest_def_cm sleep_tol_mm sleep_tol_frame_mm "
            "sleep_steps sleep_tol_max_mm pixel_mm sleep_n sleep_max_mm sleep_n_mm sleep_n_early creep_mm n_frozen "
            "sleep_s_awake sleep_s_asleep sleep_speedup air_dz_cm").split()
"""Every name the chapter glued before its computation moved here (its prose still reads each)."""
NAMES = ["data.figure2", "data.figure3.bounces", "data.figure3.time_to_rest", "data.figure3", "data.rule.bounces",
         "data.rule.time_to_rest", "data.rule.distance", "data.rule.max_height_after_1s"]
"""The results file's names of the chapter, as the old code wrote them."""


def test_the_prior_table_lists_each_class_prior_the_density_it_implies_and_the_launch_with_sources():
    cfg = synth.SynthConfig.preset("smoke").replace(
        light=synth.ClassPrior(mass=(0.2, 0.4), restitution=(0.3, 0.6), friction=(0.2, 0.5)))
    rows = data.prior_table(cfg).rows
    params = ["mass", "restitution", "friction", "density (mass / volume)"]
    assert [(r["class"], r["parameter"]) for r in rows[:8]] == [(c, p) for c in ("light", "heavy") for p in params]
    assert [r["class"] for r in rows[8:]] == ["both"] * 4
    light = {r["parameter"]: r["range"] for r in rows if r["class"] == "light"}
    assert light["mass"] == "0.2 – 0.4 kg (log-uniform)" and light["friction"] == "0.2 – 0.5 (uniform)"
    assert light["density (mass / volume)"] == "25 – 50 kg/m³", "0.2 and 0.4 kg in the 8 L cube"
    heavy = {r["parameter"]: r["range"] for r in rows if r["class"] == "heavy"}
    assert heavy["density (mass / volume)"] == "375 – 3125 kg/m³"
    assert rows[8]["range"] == f"{cfg.launch.height[0]:g} – {cfg.launch.height[1]:g} m"
    sources = " ".join(r["source"] for r in rows)
    assert not any(key in sources for key in data.CITES), "every reference is cited as the book cites it"
    restitution = next(r["source"] for r in rows if r["class"] == "heavy" and r["parameter"] == "restitution")
    assert "{cite:p}`wyllie2014rockfall`" in restitution


def _features(light: list[float], heavy: list[float], rest_light: list[float], rest_heavy: list[float]):
    y = np.array([0] * len(light) + [1] * len(heavy))
    return {"bounces": np.array(light + heavy, float), "time_to_rest": np.array(rest_light + rest_heavy, float)}, y


def test_figure3_orders_light_minus_heavy_on_the_side_of_zero_and_combines_the_two_claims():
    more = [3.0, 4.0, 3.0, 5.0, 4.0, 3.0, 4.0, 5.0]
    fewer = [0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0]
    f, y = _features(more, fewer, [2.0, 2.2, 2.4, 2.1, 2.3, 2.0, 2.2, 2.5], [1.0, 1.1, 0.9, 1.2, 1.0, 1.1, 0.8, 1.0])
    fig3 = data.figure3(f, y)
    assert fig3.bounces.value == pytest.approx(np.mean(more) - np.mean(fewer)) and fig3.bounces.lo > 0
    assert (fig3.bounces.verdict, fig3.time_to_rest.verdict, fig3.verdict.verdict) == ("reproduced",) * 3
    assert fig3.bounces.unit == "count" and fig3.time_to_rest.unit == "s"
    assert fig3.bounces.decision.inputs["in_points"] is False and fig3.bounces.decision.inputs["delta"] == 0.0

    f, y = _features(more, fewer, [1.0, 1.1, 0.9, 1.2, 1.0, 1.1, 0.8, 1.0], [2.0, 2.2, 2.4, 2.1, 2.3, 2.0, 2.2, 2.5])
    fig3 = data.figure3(f, y)  # light objects stop sooner: the second claim fails
    assert (fig3.bounces.verdict, fig3.time_to_rest.verdict, fig3.verdict.verdict) == ("reproduced", "differs",
                                                                                        "mixed")
    f, y = _features([1.0, 3.0, 0.0, 4.0], [2.0, 1.0, 3.0, 2.0], [1.0, 2.0, 1.5, 1.2], [1.4, 1.1, 2.0, 1.3])
    assert data.figure3(f, y).verdict.verdict == "inconclusive", "intervals across 0"


def test_the_best_rule_is_chosen_on_the_training_split_never_on_the_test_split():
    y = np.array([0, 0, 0, 0, 1, 1, 1, 1])
    train = {"distance": np.array([1, 2, 3, 4, 5, 6, 7, 8.0]),  # separates the training split perfectly
             "bounces": np.array([3, 3, 2, 2, 2, 0, 1, 0.0])}  # 7 of 8 (heavy if <= 1.5)
    test = {"distance": np.array([8, 7, 6, 5, 4, 3, 2, 1.0]),  # reversed on test
            "bounces": np.array([3, 3, 2, 2, 1, 0, 1, 0.0])}  # every test throw right
    rules = data.simple_rules(train, y, test, y, names=("bounces", "distance"))
    assert rules.best == "distance" and rules.rules["distance"]["test_accuracy"] == 0.0
    assert rules.rules["bounces"]["test_accuracy"] == 1.0
    numbers = rules.numbers()
    assert numbers["bounces"].what == f"test accuracy of the best threshold on {measure.FEATURES['bounces']}"
    assert numbers["distance"].value == 0.0 and numbers["bounces"].method == "bootstrap over 8 test trajectories"
    table = rules.table(numbers)
    assert table.rows[0]["rule"] == f"heavy if {measure.FEATURES['bounces']} ≤ 1.50"
    assert table.rows[1]["rule"] == f"heavy if {measure.FEATURES['distance']} > 4.50"
    assert table.rows[0]["train"] == "87.5 %" and table.rows[0]["test"].startswith("100.0 % [")


def test_energy_gained_with_friction_is_counted_per_class_and_said_in_words():
    assert data.largest_rise(np.array([2.0, 1.0, 1.2, 0.5])) == pytest.approx(0.1)
    assert data.largest_rise(np.array([2.0])) == 0.0
    gains, loses = np.array([1.0, 0.5, 0.6]), np.array([1.0, 0.5, 0.4])
    one = data.Energy((gains, loses, loses), ("light", "heavy", "heavy"), (loses,))
    assert one.gaining == {"light": (1, 1), "heavy": (0, 2)}
    assert one.by_class.startswith("It does not touch the classes alike: 1 of 1 light and 0 of 2 heavy")
    assert data.Energy((gains, gains), ("light", "heavy"), ()).by_class.startswith("It touches both classes")
    assert data.Energy((loses, loses), ("light", "heavy"), ()).by_class == "None of these throws gains energy."


def test_figure3_samples_are_drawn_within_each_class_heavy_first():
    y = np.array([0, 1, 0, 1, 1, 0, 1])
    picks = data.sample_throws(y, 2, seed=0)
    assert list(picks) == ["heavy", "light"]
    assert all(y[j] == 1 for j in picks["heavy"]) and all(y[j] == 0 for j in picks["light"])
    assert len(data.sample_throws(y, 9, seed=0)["light"]) == 3, "no more than the class has"
    assert [list(v) for v in data.sample_throws(y, 2, seed=0).values()] == [list(v) for v in picks.values()]


@pytest.fixture(scope="module")
def chapter(smoke_dataset):
    """The chapter on the smoke preset's data set; the filmstrip's frames are not rendered (no OpenGL needed)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(data.render, "filmstrip",
                   lambda cfg, params, i, times, **kw: [np.zeros((2, 2, 3), np.uint8)] * len(times))
        return data.compute(smoke_dataset, n_examples=3)


def test_the_chapter_keeps_every_name_and_its_numbers_read_back(chapter, tmp_path):
    assert [name for name, _ in chapter.numbers.entries()] == NAMES
    glued = dict(publish.glued(chapter))
    assert set(OLD_GLUE) <= set(glued), f"no longer glued: {set(OLD_GLUE) - set(glued)}"
    assert {"figure3", "figure3.bounces.verdict", "figure2", "rule.distance"} <= set(glued)
    odd = {k: type(v).__name__ for k, v in glued.items() if type(v) not in (str, int, float, data.Table)}
    assert not odd, f"a glued value must be a plain str, int or float (the page formats it): {odd}"
    f = tmp_path / "data.json"
    f.write_text(results.dumps(chapter.numbers.entries()))
    assert data.Numbers.read(results.load(f)) == chapter.numbers


def test_the_chapter_counts_what_it_checked(chapter, smoke_dataset):
    cfg, n = chapter.config, smoke_dataset.test
    assert chapter.n_test_throws == len(n) == 2 * cfg.n_test
    best = chapter.rules.rules[chapter.rules.best]
    assert best["train_accuracy"] == max(r["train_accuracy"] for r in chapter.rules.rules.values())
    assert measure.FEATURES[chapter.rules.best].startswith(chapter.best_rule)
    assert chapter.best_rule_wrong == round((1 - chapter.best_rule_acc / 100) * chapter.n_test_throws)
    per_class = min(cfg.n_train, 4), min(cfg.n_train, 16), min(cfg.n_train, 32)
    assert (chapter.n_traces, chapter.fr_n, chapter.sleep_n) == tuple(2 * k for k in per_class)
    assert chapter.contacts.classes == ("light",) * per_class[0] + ("heavy",) * per_class[0]
    assert chapter.fr_n_rise == sum(g for g, _ in chapter.energy.gaining.values())
    assert 0 <= chapter.n_still <= chapter.n_traces and 0 <= chapter.n_frozen <= chapter.sleep_n
    assert chapter.pen_max_mm < chapter.pen_bound_mm and chapter.drop_err < 0.05
    assert len(chapter.filmstrip.frames) == len(data.FILMSTRIP_TIMES) and chapter.filmstrip.lead[-1] == 0.0
    assert chapter.filmstrip.lead_z[-1] == pytest.approx(chapter.filmstrip.start_z)
    assert [len(v) for v in chapter.samples.values()] == [3, 3]
    assert len(chapter.prior_table.rows) == 12 and len(chapter.rules_table.rows) == len(data.RULES)
    assert chapter.n_total == 4000 and chapter.fig3_bounces.startswith(("+", "-"))
