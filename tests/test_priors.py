"""A user's own priors file (study.simulate.priors) and a data set of their own size from the command line."""

from __future__ import annotations

import pytest

from study import cli
from study.core.errors import ConfigError, DataError
from study.simulate.priors import read_priors
from study.simulate.synth import SynthConfig

BASE = SynthConfig.preset("smoke")


def test_a_priors_file_puts_its_ranges_over_the_presets(tmp_path):
    f = tmp_path / "mine.toml"
    f.write_text("[light]\nmass = [0.05, 0.3]\n\n[launch]\nheight = [0.8, 1.2]\nspin = 3\n")
    cfg = read_priors(f, BASE)
    assert cfg.light.mass == (0.05, 0.3) and cfg.light.friction == BASE.light.friction
    assert cfg.launch.height == (0.8, 1.2) and cfg.launch.spin == 3.0 and cfg.heavy == BASE.heavy
    j = tmp_path / "mine.json"
    j.write_text('{"heavy": {"mass": [5, 40]}}')
    assert read_priors(j, BASE).heavy.mass == (5.0, 40.0)


@pytest.mark.parametrize("text, what", [
    ("[medium]\nmass = [1, 2]\n", "unknown section [medium]"),
    ("[light]\nweight = [1, 2]\n", "[light] has no field 'weight'"),
    ("[light]\nmass = 0.3\n", "[light] mass = 0.3; give two numbers"),
    ("[light]\nmass = [0.3, 0.1]\n", "light.mass[1]"),
    ("[heavy]\nrestitution = [0.2, 1.5]\n", "heavy.restitution[1]"),
    ("[launch]\nspin = [1, 2]\n", "[launch] spin = [1, 2]; give a number"),
    ("light = 3\n", "[light] must be a table"),
])
def test_every_mistake_in_a_priors_file_names_the_file_section_and_field(tmp_path, text, what):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ConfigError) as e:
        read_priors(f, BASE)
    assert str(f) in str(e.value) and what in str(e.value)


def test_a_missing_empty_or_unreadable_priors_file_is_a_data_error(tmp_path):
    for name, text in (("none.toml", None), ("empty.toml", "  \n"), ("broken.toml", "[light\nmass = "),
                       ("broken.json", "{not json")):
        f = tmp_path / name
        if text is not None:
            f.write_text(text)
        with pytest.raises(DataError, match=str(f).replace(".", r"\.")):
            read_priors(f, BASE)


def test_study_synth_makes_a_data_set_of_ones_own_size_and_priors(tmp_path, capsys):
    from study.simulate import data

    f = tmp_path / "mine.toml"
    f.write_text("[heavy]\nmass = [5.0, 40.0]\n")
    out = tmp_path / "mine.npz"
    assert cli.main(["synth", "--preset", "smoke", "--train-per-class", "3", "--test-per-class", "2", "--priors",
                     str(f), "--out", str(out), "--no-progress"]) == 0
    ds = data.load(out)
    assert len(ds.train.y) == 6 and len(ds.test.y) == 4 and ds.meta["config"]["heavy"]["mass"] == [5.0, 40.0]
    capsys.readouterr()
    assert cli.main(["synth", "--preset", "smoke", "--train-per-class", "0", "--no-progress"]) == 2
    assert "--train-per-class 0" in capsys.readouterr().err
    f.write_text("[heavy]\nmass = [50.0, 40.0]\n")
    assert cli.main(["synth", "--preset", "smoke", "--priors", str(f), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(f) in err and "heavy.mass[1]" in err
