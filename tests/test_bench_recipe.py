"""benchmarks/bench_recipe.py chooses a recipe on validation alone: of those that settle, the cheapest of the best."""

from __future__ import annotations

import scripts_toys


def _bench():
    return scripts_toys.script("benchmarks/bench_recipe.py")


def _row(b, recipe, val, swing, epochs, failed=0, test=50.0, climb=0.0):
    return [b.Row(recipe, net, [val] * 3, [swing] * 3, [climb] * 3, [epochs] * 3, [test] * 3, failed, 10.0)
            for net in b.SCREEN]


def test_the_cheapest_of_the_settled_recipes_near_the_best_is_chosen():
    b = _bench()
    rows = (_row(b, b.BASELINE, 95.0, 30.0, 80) + _row(b, "plateau", 97.0, 1.5, 110)
            + _row(b, "cosine 60, 3e-3, warm-up 3", 96.8, 1.0, 60) + _row(b, "cosine 100, 1e-3", 95.5, 0.5, 100)
            + _row(b, "constant + EMA", 99.0, 0.5, 70, failed=1, test=99.9)
            + _row(b, "cosine 100, 1e-3, EMA", 99.5, 0.3, 100, climb=2.5))
    chosen, why = b.choose(rows)
    assert chosen == "cosine 60, 3e-3, warm-up 3", "within 0.5 points of the best settled, and fewer epochs"
    assert why[b.BASELINE] == "does not settle" and why["constant + EMA"] == "does not settle", "a failed seed"
    assert why["plateau"].startswith("the best on validation") and "below the best" in why["cosine 100, 1e-3"]
    assert why["cosine 100, 1e-3, EMA"] == "still climbing", "smooth is not flat: its curve still rises"


def test_when_nothing_settles_todays_recipe_stays():
    b = _bench()
    chosen, why = b.choose(_row(b, b.BASELINE, 95.0, 30.0, 80) + _row(b, "plateau", 97.0, 5.0, 110))
    assert chosen == b.BASELINE and "none settles" in why[b.BASELINE]


def test_a_recipe_the_seeds_cannot_tell_from_the_best_is_as_good_and_the_whole_study_counts_its_cost():
    b = _bench()

    def rows(recipe, vals, epochs, nets=None):
        return [b.Row(recipe, net, list(vals), [0.5] * 3, [0.0] * 3, [epochs] * 3, [97.0] * 3, 0, 10.0)
                for net in (nets or b.SCREEN)]

    screen = rows(b.BASELINE, (90.0, 91.0, 92.0), 80) + rows("cosine 150, 1e-3", (99.0, 97.0, 99.0), 150)
    noisy = screen + rows("constant + EMA", (97.0, 98.0, 97.2), 150)  # 1 point below, the seeds disagree
    steady = screen + rows("constant + EMA", (98.0, 96.0, 98.0), 150)  # 1 point below on every seed
    positions = rows("cosine 150, 1e-3", (70.0,) * 3, 150, b.CONFIRM) + rows("constant + EMA", (70.0,) * 3, 60, b.CONFIRM)
    chosen, why = b.choose(noisy, positions)
    assert chosen == "constant + EMA", "as good by the paired interval, and cheaper on the whole study"
    assert why["cosine 150, 1e-3"].startswith("the best on validation")
    assert b.choose(noisy)[0] == "cosine 150, 1e-3", "on the screen alone both run 150 epochs: the better wins"
    chosen, why = b.choose(steady, positions)
    assert chosen == "cosine 150, 1e-3" and "below the best [1.0, 1.0]" in why["constant + EMA"]


def test_a_recipe_whose_seed_fails_on_the_confirmation_is_not_chosen():
    b = _bench()

    def rows(recipe, val, epochs, nets, failed=0):
        return [b.Row(recipe, net, [val] * 3, [0.5] * 3, [0.0] * 3, [epochs] * 3, [97.0] * 3, failed, 10.0)
                for net in nets]

    screen = rows("cosine 150, 1e-3", 98.0, 150, b.SCREEN) + rows("constant + EMA", 98.0, 150, b.SCREEN)
    confirm = rows("cosine 150, 1e-3", 70.0, 150, b.CONFIRM) + rows("constant + EMA", 70.0, 80, b.CONFIRM, failed=1)
    trained = rows("cosine 150, 1e-3", 70.0, 150, b.CONFIRM) + rows("constant + EMA", 70.0, 80, b.CONFIRM)
    assert b.choose(screen, trained)[0] == "constant + EMA", "cheaper where nothing failed"
    chosen, why = b.choose(screen, confirm)
    assert chosen == "cosine 150, 1e-3" and why["constant + EMA"].startswith("a seed failed")
