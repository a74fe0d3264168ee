"""How far an answer can be trusted (study.trust) and the recommended model's cannot-tell band
(study.methods.recommend.band): known answers on tiny inputs."""

from __future__ import annotations

import numpy as np
import pytest

from study import trust
from study.core.errors import ModelError
from study.learn.metrics import Interval
from study.methods import operating, recommend
from study.runs import measured, recommended

IV = Interval(0.642, 0.529, 0.75, "test")


def test_a_band_leaves_each_class_at_most_its_certified_share_of_the_other():
    rng = np.random.default_rng(0)
    y = np.repeat([0, 1], 1000)
    p = np.clip(np.where(y == 1, 0.65, 0.35) + rng.normal(0, 0.15, y.size), 0, 1)  # classes overlap
    lo, hi = recommend.band(p, y, target=0.05)
    assert 0 < lo < 0.5 < hi < 1
    k_max = max(k for k in range(1000) if operating.clopper_pearson_upper(k, 1000) <= 0.05)
    assert (p[y == 1] < lo).sum() <= k_max, "an answer of light lets through at most the certified heavy ones"
    assert (p[y == 0] > hi).sum() <= k_max, "an answer of heavy at most the certified light ones"
    assert (p[y == 1] < lo + 1e-3).sum() > k_max, "and the low side is the highest that does"


def test_a_band_is_none_when_the_classes_separate_and_everything_when_too_few_to_certify():
    y = np.repeat([0, 1], 1000)
    assert recommend.band(np.where(y == 1, 0.9, 0.1), y, target=0.05) is None
    assert recommend.band(np.where(y[::100] == 1, 0.9, 0.1), y[::100], target=0.05) == (0.0, 1.0), "20 throws"


def test_an_answer_inside_the_band_is_cannot_tell_and_outside_it_the_likelier_class():
    t = trust.Trust(IV, "test", (0.3, 0.7))
    assert [t.label(p) for p in (0.29, 0.3, 0.5, 0.7, 0.71)] == ["light", *[trust.CANNOT_TELL] * 3, "heavy"]
    assert trust.Trust(IV, "test").label(0.51) == "heavy" and trust.Trust(IV, "test").label(0.5) == "light"  # heavy above 1/2
    said = str(t)
    assert said.startswith("64.2 % [52.9, 75.0] right (test)") and "cannot tell for p(heavy) 0.300-0.700" in said


def test_the_band_is_printed_as_finely_as_the_answer_so_an_answer_inside_it_reads_inside_it():
    t = trust.Trust(IV, "test", (0.19701, 0.8155))  # the paper build's floor band at fe15f1e; an answer said 0.198
    assert t.label(0.198) == trust.CANNOT_TELL and "cannot tell for p(heavy) 0.197-0.816" in str(t)


def _rec(measured):
    return recommended.Recommended("paper", {}, "k", measured)


def test_an_answer_quotes_what_the_sweep_measured_for_its_kind_and_path_or_says_why_not(tmp_path, monkeypatch):
    rec = trust.measurements(_rec({"velocity-any-camera": {"exact": IV, "mean": IV}}))
    got = trust.for_answer("velocity-any-camera", "mean", rec)
    assert got.accuracy == IV and "paper build" in got.source and "mean silhouette path" in got.source
    assert trust.for_answer("velocity-any-camera", "gravity", rec).accuracy is None
    assert "floor marks path (not measured there)" in trust.for_answer("velocity-any-camera", trust.FLOOR, rec).source
    missing = trust.for_answer("positions-fixed", "mean", rec)
    assert missing.accuracy is None and "no model of this kind (positions-fixed" in missing.source
    assert "a scale you measured" in trust.for_answer("velocity-any-camera", trust.MEASURED_SCALE, rec).source
    monkeypatch.setattr(measured, "SHIPPED", tmp_path / "none.json")
    alone = trust.for_answer("velocity-any-camera", "mean", trust.measurements(None))
    assert alone.accuracy is None and "build the book" in alone.source and "mean silhouette path" in alone.source
    smoke = recommended.Recommended("smoke", {}, "k", {"velocity-any-camera": {"mean": IV}})
    assert trust.measurements(smoke, answering=True).measured, "a build's own model: its own numbers"
    assert not trust.measurements(smoke).measured, "a smoke build's numbers never weigh a model it did not make"


def test_the_shipped_copy_reads_back_and_a_broken_one_is_named(tmp_path, monkeypatch):
    path = tmp_path / "measured.json"
    shipped = measured.Shipped("abc1234", "paper", 80, {"velocity-exact": {"mean": IV}, "velocity-fixed": {"mean": IV}})
    assert shipped.span("mean") == "64.2-64.2 %" and shipped.span("floor") == ""
    assert measured.read_shipped(measured.write_shipped(path, shipped)) == shipped
    monkeypatch.setattr(measured, "SHIPPED", path)
    got = trust.for_answer("velocity-exact", "mean", trust.measurements(None))
    assert got.accuracy == IV and "paper build of abc1234, 80 clips" in got.source
    warned = trust.exact_warning("velocity-exact", "model m", trust.measurements(None))
    assert warned is not None and "exact trajectories" in warned and "64.2 % [52.9, 75.0]" in warned
    assert "--observe any-camera" in warned and trust.exact_warning("velocity-any-camera", "model m", trust.measurements(None)) is None
    itself = trust.exact_warning("velocity-exact", "the recommended model", trust.measurements(None), "floor", True)
    assert "use the recommended model" not in itself and "--observe any-camera" in itself, "not itself as the cure"
    assert "64.2" not in itself, "the floor path's own number, and the sweep measured none for it here"
    floor_iv = Interval(0.7, 0.6, 0.8, "test")
    monkeypatch.setattr(measured, "SHIPPED", measured.write_shipped(
        tmp_path / "floor.json", measured.Shipped("abc1234", "paper", 80, {"velocity-exact": {"mean": IV, "floor": floor_iv}})))
    on_floor = trust.exact_warning("velocity-exact", "model m", trust.measurements(None), "floor")
    assert "70.0 % [60.0, 80.0]" in on_floor and "through the floor marks path" in on_floor, on_floor
    scaled = trust.exact_warning("velocity-exact", "model m", trust.measurements(None), trust.MEASURED_SCALE)
    assert "64.2 % [52.9, 75.0]" in scaled, "a scale the user measured: the one-scale path's number"
    path.write_text('{"format": "study.measured/1"}')
    with pytest.raises(ModelError, match=f"{path} cannot be read"):
        measured.read_shipped(path)


def test_a_cannot_tell_counts_neither_right_nor_wrong():
    from study.answer import Answer, FolderAnswer

    a = Answer("v.mp4", trust.CANNOT_TELL, 0.6, 0.6, "m", "", None, (), trust.Trust(IV, "test", (0.3, 0.7)))  # type: ignore[arg-type]
    row = FolderAnswer("v.mp4", "heavy", a)
    assert row.correct is None and row.row()["correct"] == "" and "cannot tell for" in row.row()["trust"]
    assert FolderAnswer("v.mp4", "light", a.__class__(**{**a.__dict__, "label": "heavy"})).correct is False


def test_classify_help_quotes_the_shipped_measurements_or_says_there_are_none(tmp_path, monkeypatch, capsys):
    from study import cli

    def help_text() -> str:
        with pytest.raises(SystemExit):
            cli.main(["classify", "--help"])
        return " ".join(capsys.readouterr().out.split())

    monkeypatch.setattr(measured, "SHIPPED", tmp_path / "none.json")
    assert "ships no such measurement" in help_text()
    low = Interval(0.525, 0.41, 0.64, "test")
    measured.write_shipped(tmp_path / "m.json", measured.Shipped(
        "abc1234", "paper", 80, {"velocity-exact": {"mean": low, "exact": IV}, "velocity-any-camera": {"mean": IV}}))
    monkeypatch.setattr(measured, "SHIPPED", tmp_path / "m.json")
    said = help_text()
    assert "On the paper build of abc1234, 80 clips from random cameras" in said
    assert "labelled 52.5-64.2 % of the throws right through one scale, an unmeasured share through floor" in said


def test_with_floor_marks_the_recommended_floor_model_answers_with_its_own_band_and_kind(tmp_path):
    """A build that recommends a model for each path: floor marks pick the floor path's (its band, its kind named
    by what it was chosen for), none pick the one-scale one; a build with no floor model answers with its one-scale
    model and says so."""
    import dataclasses

    import model_toys

    from study import answer
    from study.learn import train

    ds = model_toys.dataset(n=16, T=20)
    cfg = train.TrainConfig(dims="z", length=0.5, hidden=4, epochs=1, batch_size=8, truncation=5)
    one, fl = (train.fit(ds, dataclasses.replace(cfg, seed=s), progress=False, warn=False).save(tmp_path / f"m{s}")
               for s in (0, 1))
    paths = {recommended.ONE_SCALE: recommended.PathModel("positions, any-camera", (one,), IV, band=(0.4, 0.6)),
             recommended.FLOOR: recommended.PathModel("positions, floor", (fl,), IV, band=(0.45, 0.55))}
    recommended.save(tmp_path, "smoke", paths, "k", {"positions-floor": {trust.FLOOR: IV}})
    got = answer._model(None, tmp_path, floor=True)
    assert got.recommended_for == recommended.FLOOR and got.kind == "positions-floor"
    assert got.model.members[0].config.seed == 1, "the floor path's model folder"
    assert got.band_for(trust.FLOOR) == (0.45, 0.55) and got.band_for("mean") is None, "its band on its own path only"
    assert trust.for_answer(got.kind, trust.FLOOR, got.seen, got.band_for(trust.FLOOR)).accuracy == IV
    plain = answer._model(None, tmp_path)
    assert plain.recommended_for == recommended.ONE_SCALE and plain.band_for("mean") == (0.4, 0.6)
    assert plain.band_for(trust.FLOOR) is None and plain.kind == "positions-any-camera"
    assert plain.model.members[0].config.seed == 0
    recommended.save(tmp_path, "smoke", {recommended.ONE_SCALE: paths[recommended.ONE_SCALE]}, "k", {})
    fallback = answer._model(None, tmp_path, floor=True)
    assert fallback.recommended_for == recommended.ONE_SCALE and "recommends none for the floor path" in fallback.which
    assert fallback.band_for(trust.FLOOR) is None, "a one-scale band says nothing of floor heights"


def test_print_shows_an_answers_warnings_and_the_manifest_csv_keeps_them():
    """A Python user who prints the answer sees what makes it doubtful; the command line prints those apart."""
    from study.answer import Answer, FolderAnswer

    a = Answer("v.mp4", "heavy", 0.9, 0.9, "m", "scale 1 mm/px", None, ("seed 1 failed", "exact model"),  # type: ignore[arg-type]
               trust.Trust(IV, "test"))
    assert str(a).endswith("  warning: seed 1 failed\n  warning: exact model") and "warning" not in a.text(False)
    assert FolderAnswer("v.mp4", "heavy", a).row()["warnings"] == "seed 1 failed | exact model"
    assert FolderAnswer("v.mp4", "heavy", None, "no track").row()["warnings"] == ""
