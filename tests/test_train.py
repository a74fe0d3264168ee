"""Training: determinism, truncated BPTT, save/load, evaluation, every bad input, the CLI."""

import dataclasses
import json
import math
import re

import model_toys
import numpy as np
import pytest
import torch

from study import cli
from study.core.errors import ConfigError, ModelError, TrajectoryError
from study.core.fielddoc import field_docs
from study.learn import train
from study.learn import stack  # noqa: F401
from study.learn.config import CELLS, OLD_MEANING, TrainConfig
from study.simulate import data

TINY = train.TrainConfig(dims="xyz", length=0.5, hidden=8, epochs=2, batch_size=8, truncation=5, patience=2)


@pytest.fixture(scope="module")
def ds() -> data.Dataset:
    return model_toys.dataset(n=24, T=20)


@pytest.fixture(scope="module")
def tm(ds) -> train.TrainedModel:
    return train.fit(ds, TINY, progress=False)


def _weights(m: train.TrainedModel) -> bytes:
    return b"".join(v.numpy().tobytes() for v in m.net.state_dict().values())


def test_same_seed_same_weights_bitwise(ds, tm):
    rng = torch.get_rng_state()
    again = train.fit(ds, TINY, progress=False)
    assert _weights(again) == _weights(tm)
    assert again.history == tm.history
    assert torch.equal(torch.get_rng_state(), rng), "fit leaves the caller's RNG alone"
    other = train.fit(ds, dataclasses.replace(TINY, seed=1), progress=False)
    assert _weights(other) != _weights(tm)


def test_history_and_contract(ds, tm):
    assert tm.dims == "xyz" and tm.fps == 30.0 and tm.n_frames == 15 and tm.data_key == "toy"
    assert 1 <= len(tm.history) <= TINY.epochs
    assert set(tm.history[0]) == {"epoch", "train_loss", "val_loss", "val_accuracy", "lr"}
    assert tm.diverged_epoch is None
    p = tm.predict_proba(ds.test.x)
    assert p.shape == (24, 2) and p.dtype == np.float64
    np.testing.assert_allclose(p.sum(axis=1), 1.0, atol=1e-6)


def test_normalisation_uses_the_training_part_only(ds, tm):
    tr, _ = train.split_train_val(len(ds.train.y), TINY.val_fraction, TINY.seed)
    expect = ds.train.x[tr, :15].reshape(-1, 3).astype(np.float64).std(axis=0)
    np.testing.assert_allclose(tm.net.features.std.numpy(), expect, rtol=1e-6)


def test_validation_split_is_seeded_and_disjoint():
    a_tr, a_va = train.split_train_val(50, 0.2, seed=3)
    b_tr, b_va = train.split_train_val(50, 0.2, seed=3)
    assert np.array_equal(a_va, b_va) and len(a_va) == 10
    assert not set(a_tr) & set(a_va) and len(a_tr) + len(a_va) == 50
    assert not np.array_equal(train.split_train_val(50, 0.2, seed=4)[1], a_va)


@pytest.mark.parametrize("k", [3, 8, 100])
def test_truncated_bptt_reaches_only_the_last_k_frames(k):
    torch.manual_seed(0)
    net = train.Classifier(3, hidden=6).double().eval()
    x = torch.randn(2, 8, 3, dtype=torch.float64, requires_grad=True)
    stack.last_logits(net, x, truncation=k).sum().backward()
    reached = x.grad.abs().sum(dim=(0, 2)) > 0  # (T,)
    first = max(0, 8 - k)
    assert not reached[:first].any() and reached[first:].all()
    with torch.no_grad():  # truncation changes gradients, never the prediction
        torch.testing.assert_close(stack.last_logits(net, x, k), net(x), atol=1e-12, rtol=0)


def test_save_load_round_trip(tmp_path, ds, tm):
    out = tm.save(tmp_path / "m")
    assert sorted(p.name for p in out.iterdir()) == sorted(train.FILES)
    back = train.load(out)
    assert back.config == tm.config and back.fps == tm.fps and back.data_key == "toy"
    assert back.history == tm.history and back.best_epoch == tm.best_epoch
    assert back.predict_proba(ds.test.x).tobytes() == tm.predict_proba(ds.test.x).tobytes()
    tm.save(out)  # overwriting an existing directory works and leaves no temporary behind
    assert [p.name for p in tmp_path.iterdir()] == ["m"]
    assert torch.load(out / "weights.pt", weights_only=True).keys() == tm.net.state_dict().keys()


@pytest.mark.parametrize("name", train.FILES)
def test_model_dir_missing_a_file(tmp_path, tm, name):
    out = tm.save(tmp_path / "m")
    (out / name).unlink()
    with pytest.raises(ModelError, match=name):
        train.load(out)


def test_model_dir_bad_contents(tmp_path, tm):
    with pytest.raises(ModelError, match="no such directory"):
        train.load(tmp_path / "none")
    (tmp_path / "weights.pt").write_bytes(b"x")
    with pytest.raises(ModelError, match="is a file; give the model's directory"):  # said "no such directory" before
        train.load(tmp_path / "weights.pt")
    out = tm.save(tmp_path / "m")
    (out / "weights.pt").write_bytes(b"garbage")
    with pytest.raises(ModelError, match="weights.pt"):
        train.load(out)
    out = tm.save(tmp_path / "m")
    cfg = json.loads((out / "config.json").read_text())
    (out / "config.json").write_text(json.dumps(dict(cfg, hidden=16)))
    with pytest.raises(ModelError, match="does not match"):
        train.load(out)
    (out / "config.json").write_text(json.dumps(dict(cfg, colour="red")))
    with pytest.raises(ModelError, match="config.json"):
        train.load(out)


def test_bad_config_is_refused_where_it_is_made():
    for bad, match in [(dict(dims="xy"), "dims"), (dict(length=0.0), "length"), (dict(length=-1.0), "length"),
                       (dict(cell="rnn"), "cell"), (dict(truncation=0), "truncation"), (dict(dropout=1.0), "dropout"),
                       (dict(rotate=-1.0), "rotate"), (dict(rotate=181.0), "rotate"),
                       (dict(rotate=90.0, dims="z"), "rotate .* dims 'z'"), (dict(inputs="heading"), "inputs"),
                       (dict(dims="Z"), "dims = 'Z' is unknown; use 'z' \\(lower case\\)"),
                       (dict(epochs=0), "TrainConfig.epochs"), (dict(observe="Any-Camera"), "use 'any-camera'"),
                       (dict(plateau_epochs=0), "TrainConfig.plateau_epochs = 0; it must be a whole number")]:
        with pytest.raises(ConfigError, match=match):  # at construction: before, dims="Z" failed only at fit
            dataclasses.replace(TINY, **bad)


def test_the_epoch_budget_has_one_name_everywhere():
    assert TrainConfig(epochs=7).epochs == 7  # the --epochs flag's name; TrainConfig(epochs=...) was refused before
    with pytest.raises(TypeError, match="max_epochs"):
        TrainConfig(max_epochs=7)


def test_bad_data(ds, tm):
    with pytest.raises(TrajectoryError, match="20 frames, but the model needs 30"):
        train.fit(ds, dataclasses.replace(TINY, length=1.0), progress=False)
    x = ds.train.x.copy()
    x[5, 3, 2] = np.nan
    nan_ds = data.Dataset(train=data.Split(x, ds.train.y), test=ds.test, fps=30.0)
    with pytest.raises(TrajectoryError, match="index 5"):
        train.fit(nan_ds, TINY, progress=False)
    with pytest.raises(TrajectoryError, match="needs 15"):
        tm.predict_proba(ds.test.x[:, :10])
    with pytest.raises(TrajectoryError, match="shape"):
        tm.predict_proba(ds.test.x[:, :, :2])


def test_metrics_confusion_rows_true_cols_predicted():
    m = train.metrics(np.array([0, 0, 0, 1, 1]), np.array([0, 1, 1, 1, 1]))
    assert m["confusion"] == [[1, 2], [0, 2]]
    assert m["accuracy"] == pytest.approx(0.6)
    assert m["per_class_accuracy"] == {"light": pytest.approx(1 / 3), "heavy": 1.0}
    assert math.isnan(train.metrics(np.array([1]), np.array([1]))["per_class_accuracy"]["light"])


@pytest.mark.slow
def test_learns_the_toy_problem():
    ds = model_toys.dataset(n=64, T=45)
    cfg = train.TrainConfig(dims="z", length=1.5, hidden=16, epochs=15, batch_size=16, lr=1e-2, patience=15)
    tm = train.fit(ds, cfg, progress=False)
    assert train.evaluate(tm, ds.test)["accuracy"] >= 0.8


def test_cli_options_are_the_train_config_fields(capsys):
    """`study train` offers every TrainConfig field, with the field's default, its docstring as help and its
    Literal's values as choices."""
    args = cli.build_parser().parse_args(["train", "--data", "d.npz", "--out", "m"])
    for f in dataclasses.fields(train.TrainConfig):
        assert getattr(args, f.name) == f.default, f.name
    with pytest.raises(SystemExit):
        cli.main(["train", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    names = {f.name for f in dataclasses.fields(train.TrainConfig)}
    as_typed = lambda m: "--" + m[1].replace("_", "-") if m[1] in names else f"'{m[1]}'"  # noqa: E731
    for f in dataclasses.fields(train.TrainConfig):  # another field named in a docstring reads as its flag
        doc = re.sub(r"``(.+?)``", as_typed, " ".join(field_docs(train.TrainConfig)[f.name].split()))
        assert doc[:30] in help_text, f.name
    with pytest.raises(SystemExit):
        cli.build_parser().parse_args(["train", "--data", "d", "--out", "m", "--cell", "transformer"])
    err = capsys.readouterr().err
    assert "invalid choice: 'transformer'" in err and all(repr(c) in err for c in CELLS)


@pytest.mark.slow
def test_cli_train_and_evaluate(tmp_path, smoke_dataset, capsys):
    path = str(smoke_dataset.path)
    args = ["train", "--data", path, "--dims", "z", "--length", "0.5", "--epochs", "1", "--batch-size", "8",
            "--out", str(tmp_path / "m"), "--no-progress"]
    assert cli.main(args) == 0
    got = capsys.readouterr()
    out = json.loads(got.out)
    assert out["model"] == str(tmp_path / "m") and out["failed"] is True, "3 validation throws cannot show learning"
    assert out["val_accuracy_interval"]["lo"] <= out["val_accuracy"] <= out["val_accuracy_interval"]["hi"]
    assert f"{int(np.bincount(smoke_dataset.train.y).min())} training throws a class" in got.err
    assert "study synth --train-per-class 200" in got.err, "a smoke-sized data set says how many throws it needs"
    assert cli.main(["evaluate", "--model", str(tmp_path / "m"), "--data", path]) == 0
    res = json.loads(capsys.readouterr().out)
    assert set(res["per_class_accuracy"]) == {"light", "heavy"} and np.sum(res["confusion"]) == len(smoke_dataset.test)
    assert res["trained_on"] == res["data_key"] == smoke_dataset.key
    iv = res["accuracy_interval"]  # a number without its spread is not a result
    assert iv["lo"] <= res["accuracy"] <= iv["hi"] and iv["hi"] - iv["lo"] > 0.1, "a handful of test throws: wide"
    assert iv["method"].startswith("Wilson interval, ")
    assert train.load(tmp_path / "m").dims == "z"


def test_cli_bad_input_one_line_exit_2(tmp_path, smoke_dataset, capsys):
    path = str(smoke_dataset.path)
    assert cli.main(["train", "--data", path, "--dims", "z", "--length", "5", "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "needs 150" in err
    assert not (tmp_path / "m").exists(), "nothing left behind"
    assert cli.main(["evaluate", "--model", str(tmp_path / "none"), "--data", path]) == 2
    assert "no such directory" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        cli.main(["train", "--data", path, "--dims", "xy", "--length", "1", "--out", str(tmp_path / "m")])


def test_a_run_that_cannot_learn_says_it_failed(ds):
    rng = np.random.default_rng(0)
    shuffled = dataclasses.replace(ds, train=dataclasses.replace(ds.train, y=rng.permutation(ds.train.y)))
    cfg = dataclasses.replace(TINY, dims="z", epochs=3, min_epochs=0)
    with pytest.warns(train.TrainingFailedWarning, match=r"failed to train.*a lower lr \(the protocol"):
        tm = train.fit(shuffled, cfg, progress=False)
    assert tm.failed and "never left the initial plateau" in tm.failure()


@pytest.mark.slow
def test_the_defaults_train(tmp_path):
    """TrainConfig's defaults are a protocol that trains: a run with them on a task a network can learn is not
    reported failed, and its model says so when saved and loaded."""
    import warnings

    toy = model_toys.dataset(n=128, T=90)  # 3 s at 30 fps: the default input length
    with warnings.catch_warnings():
        warnings.simplefilter("error", train.TrainingFailedWarning)
        tm = train.fit(toy, train.TrainConfig(), progress=False)
    assert not tm.failed and tm.failure() == "" and tm.n_val == 26
    assert not train.load(tm.save(tmp_path / "m")).failed


# --- the training protocol: forget bias, early stopping, clipping, schedule, divergence --------------

FROZEN = dataclasses.replace(TINY, lr=1e-12, dims="z")  # steps too small to change a float32 weight


@torch.no_grad()
def _forget_biases(net) -> torch.Tensor:
    H = net.head.in_features
    if net.cell_type in ("peephole", "no-peephole"):
        return torch.stack([layer.bias[H : 2 * H] for layer in net.rnn.layers])
    return torch.stack([getattr(net.rnn, f"bias_ih_l{k}")[H : 2 * H] + getattr(net.rnn, f"bias_hh_l{k}")[H : 2 * H]
                        for k in range(net.rnn.num_layers)])


@pytest.mark.parametrize("cell", ["peephole", "no-peephole", "torch-lstm"])
def test_forget_bias_is_added_to_every_forget_gate(cell):
    from study.learn.model import Classifier

    torch.manual_seed(0)
    a = Classifier(3, hidden=8, cell=cell)
    b = Classifier(3, hidden=8, cell=cell)
    b.load_state_dict(a.state_dict())
    b.init_forget_gates(1.0)
    torch.testing.assert_close(_forget_biases(b), _forget_biases(a) + 1.0)
    before = {k: v.clone() for k, v in a.state_dict().items()}
    a.init_forget_gates(0.0)
    assert all(torch.equal(before[k], v) for k, v in a.state_dict().items())


@pytest.mark.parametrize("cell", ["peephole", "torch-lstm"])
def test_chrono_initialisation_spans_the_input(cell):
    from study.learn.model import Classifier

    torch.manual_seed(0)
    net = Classifier(1, hidden=64, cell=cell)
    net.init_forget_gates(0.0, chrono_frames=240)
    f = _forget_biases(net)
    assert f.min() >= 0 and f.max() <= np.log(239) + 1e-5 and f.max() > np.log(100)  # log U(1, T - 1)
    H = 64
    layer_bias = net.rnn.layers[0].bias if cell == "peephole" else net.rnn.bias_ih_l0
    torch.testing.assert_close(layer_bias[:H], -layer_bias[H : 2 * H])  # input gate: the negative


def test_gru_has_no_forget_gate_to_initialise():
    from study.learn.model import Classifier

    torch.manual_seed(0)
    net = Classifier(1, hidden=8, cell="gru")
    before = {k: v.clone() for k, v in net.state_dict().items()}
    net.init_forget_gates(1.0, chrono_frames=50)
    assert all(torch.equal(before[k], v) for k, v in net.state_dict().items())


def test_fit_starts_from_the_configured_forget_bias(ds):
    def mean_forget(bias):
        tm = train.fit(ds, dataclasses.replace(FROZEN, forget_bias=bias, epochs=1), progress=False)
        return float(_forget_biases(tm.net).mean())

    assert mean_forget(1.0) == pytest.approx(mean_forget(0.0) + 1.0, abs=1e-4)


@pytest.mark.parametrize("plateau_epochs, expected", [(1, 1), (6, 6)])
def test_a_run_on_the_plateau_stops_after_its_plateau_allowance(ds, plateau_epochs, expected):
    """No weight moves, so the validation loss never leaves the plateau: the run stops once ``plateau_epochs``
    have passed, whatever its minimum and patience, keeping its first epoch."""
    cfg = dataclasses.replace(FROZEN, patience=1, min_epochs=0, plateau_epochs=plateau_epochs, epochs=10)
    tm = train.fit(ds, cfg, progress=False)
    assert tm.history[0]["val_loss"] > train.PLATEAU_LOSS, "the toy's frozen run is on the plateau"
    assert len(tm.history) == expected and tm.best_epoch == 0


def _driven(ds, cfg: train.TrainConfig, val_losses: list[float]):
    """A run shown ``val_losses`` epoch by epoch through :func:`train.end_epoch`: the run after each epoch."""
    r = train.Run(train.stack.member(ds, cfg, torch.device("cpu")))
    for epoch, loss in enumerate(val_losses):
        train.end_epoch(r, epoch, loss, 0.5)
        yield r


def _stops(ds, cfg: train.TrainConfig, val_losses: list[float]) -> int | None:
    """The epoch after which :func:`train.end_epoch` stops a run shown ``val_losses`` (None: never)."""
    return next((epoch for epoch, r in enumerate(_driven(ds, cfg, val_losses)) if r.done), None)


def test_patience_counts_from_the_epoch_the_loss_leaves_the_plateau(ds):
    """The velocity-Z run of the last cold build: on the plateau for 30 epochs, a blip at epoch 6 its best. Today
    that blip cannot end it at the minimum; leaving the plateau at epoch 35, it trains on from there."""
    cfg = dataclasses.replace(TINY, epochs=200, patience=20, min_epochs=30, plateau_epochs=50)
    flat = [0.6931] * 60
    flat[6] = 0.680  # the blip: lower than any other epoch, still on the plateau (PLATEAU_LOSS is 0.624)
    assert _stops(ds, cfg, flat) == 49, "never left: stops after plateau_epochs, not at the minimum (29)"
    leaving = flat[:35] + [0.60 - 0.01 * k for k in range(20)] + [0.45] * 40
    assert _stops(ds, cfg, leaving) == 54 + 20, "patience from its best after leaving"
    early = [0.69, 0.5, 0.4] + [0.41] * 60
    assert _stops(ds, cfg, early) == 29, "left at once, best at 2: patience runs out at 22, the minimum holds to 29"
    late_best = [0.69, 0.5] + [0.45] * 20 + [0.40] + [0.45] * 40
    assert _stops(ds, cfg, late_best) == 22 + 20


def test_a_slow_starter_gets_the_plateau_allowance_to_leave_the_plateau(ds):
    """Table 1's X, Y, Z seed 0 of the cold build at 16ca2b0 left the plateau at epoch 56: the old rule (min_epochs
    + patience = 50) cut it as a failure; the study's allowance (100) lets it train, and still ends a run that
    never leaves."""
    cfg = dataclasses.replace(TINY, epochs=150, patience=20, min_epochs=30)
    assert cfg.plateau_epochs == TrainConfig().plateau_epochs == 100
    slow = [0.69] * 56 + [0.60 - 0.01 * k for k in range(15)] + [0.46] * 80
    assert _stops(ds, dataclasses.replace(cfg, plateau_epochs=50), slow) == 49, "the old rule: failed at 50"
    assert _stops(ds, cfg, slow) == 70 + 20, "left at 56, best at 70: patience from there"
    assert _stops(ds, cfg, [0.69] * 150) == 99, "never leaves: stops after the allowance"


def _rates(ds, cfg: train.TrainConfig, val_losses: list[float]) -> list[float]:
    """The learning rate after each epoch of a run shown ``val_losses`` (:func:`_driven`)."""
    return [r.opt.param_groups[0]["lr"] for r in _driven(ds, cfg, val_losses)]


def test_plateau_schedule_halves_the_rate_when_validation_stalls_after_leaving_the_plateau(ds):
    """The protocol comparison's XYZ seed 1 of the cold build at 9217b0c: its rate halved every 6 epochs while it
    sat on the initial plateau, to 1/256 from epoch 49, and it never left. Today the schedule waits, as patience
    does, until the loss has left the plateau; after that a stall of more than ``patience // 4`` epochs halves it."""
    cfg = dataclasses.replace(TINY, lr=1e-3, lr_schedule="plateau", patience=20, epochs=200)
    on_plateau = [0.6931] * 40
    assert _rates(ds, cfg, on_plateau) == [1e-3] * 40, "no halving while on the plateau"
    left = [0.6931] * 10 + [0.5, 0.45] + [0.46] * 12
    rates = _rates(ds, cfg, left)
    assert rates[:17] == [1e-3] * 17, "best at epoch 11; 5 epochs without a lower loss are allowed"
    assert rates[17] == pytest.approx(5e-4) and rates[-1] < rates[17], "then it halves, and again"
    assert _rates(ds, dataclasses.replace(cfg, lr_schedule="constant"), left) == [1e-3] * len(left)


def test_plateau_schedule_halves_the_rate_in_training(ds):
    """The real loop: the rate holds until the loss leaves the plateau, and a stall after that halves it (the
    toy's loss leaves the plateau within its first epochs at this rate)."""
    cfg = dataclasses.replace(TINY, lr=3e-2, lr_schedule="plateau", patience=4, min_epochs=30, epochs=30,
                              plateau_epochs=30)
    tm = train.fit(ds, cfg, progress=False, warn=False)
    lrs = [h["lr"] for h in tm.history]
    left = next(i for i, h in enumerate(tm.history) if h["val_loss"] < train.PLATEAU_LOSS)  # the toy run leaves it
    assert all(lr == cfg.lr for lr in lrs[: left + 1]), "no halving before it leaves"
    assert lrs[0] == cfg.lr and lrs[-1] < lrs[0] and all(b <= a for a, b in zip(lrs, lrs[1:]))


def test_clipping_bounds_the_gradient_each_step_sees(ds, monkeypatch):
    norms: list[float] = []
    step = torch.optim.Adam.step

    def recording_step(self, *args, **kwargs):
        grads = [p.grad for group in self.param_groups for p in group["params"] if p.grad is not None]
        norms.append(float(torch.linalg.vector_norm(torch.stack([torch.linalg.vector_norm(g) for g in grads]))))
        return step(self, *args, **kwargs)

    monkeypatch.setattr(torch.optim.Adam, "step", recording_step)
    train.fit(ds, dataclasses.replace(TINY, dims="z", epochs=1, clip_norm=1e-3), progress=False)
    assert norms and max(norms) <= 1e-3 * (1 + 1e-5)
    norms.clear()
    train.fit(ds, dataclasses.replace(TINY, dims="z", epochs=1), progress=False)
    assert max(norms) > 1e-2  # unclipped, the gradients are far larger


def test_a_diverged_run_says_so_and_keeps_finite_weights(ds, tmp_path):
    cfg = dataclasses.replace(TINY, dims="z", lr=1e30, epochs=5, min_epochs=5)
    tm = train.fit(ds, cfg, progress=False)
    assert tm.diverged_epoch is not None and math.isnan(tm.history[-1]["train_loss"])
    assert all(torch.isfinite(v).all() for v in tm.net.state_dict().values())
    assert train.load(tm.save(tmp_path / "m")).diverged_epoch == tm.diverged_epoch


def _as_old_format(folder, version: int) -> None:
    """Rewrite a saved model directory as format 1, 2, 3, 5 or 6 wrote it: no plateau allowance; before format 6 the
    budget named ``max_epochs``; before format 4 none of its fields (``rotate``, ...); before format 3 the std as
    the state dict's 'scale' and no 'inputs' field (and, for format 1, none of the protocol fields)."""
    cfg = json.loads((folder / "config.json").read_text())
    del cfg["plateau_epochs"]
    if version < 6:
        cfg["max_epochs"] = cfg.pop("epochs")
    for name in OLD_MEANING[3] if version <= 3 else ():  # what format 4 added
        del cfg[name]
    if version < 3:
        state = torch.load(folder / "weights.pt", weights_only=True)
        state["scale"] = state.pop("features.std")
        del state["features.mean"]
        torch.save(state, folder / "weights.pt")
        del cfg["inputs"]
    for name in ("min_epochs", "forget_bias", "forget_init", "clip_norm", "lr_schedule") if version == 1 else ():
        del cfg[name]
    (folder / "config.json").write_text(json.dumps(cfg))
    meta = json.loads((folder / "meta.json").read_text())
    (folder / "meta.json").write_text(json.dumps({**meta, "format": f"study.model/{version}"}))


@pytest.mark.parametrize("version", [1, 2, 3, 5, 6])
def test_an_old_format_model_reads_as_positions_with_its_old_meaning(tm, ds, tmp_path, version):
    folder = tm.save(tmp_path / "old")
    assert json.loads((folder / "meta.json").read_text())["format"] == train.FORMAT == "study.model/7"
    _as_old_format(folder, version)
    old = train.load(folder)
    assert old.config.inputs == "positions" and old.net.features.inputs == "positions"
    assert old.config.rotate == 0.0, "no model before format 4 was trained on turned throws"
    np.testing.assert_array_equal(old.predict_proba(ds.test.x), tm.predict_proba(ds.test.x))
    if version == 1:
        assert (old.config.forget_bias, old.config.min_epochs, old.config.clip_norm) == (0.0, 0, 0.0)
    assert old.config.epochs == tm.config.epochs, "saved as max_epochs before format 6"
    assert old.config.plateau_epochs == old.config.min_epochs + old.config.patience, "the plateau's stop before 7"


def test_a_model_that_lacks_a_field_of_its_format_is_refused(tm, tmp_path):
    folder = tm.save(tmp_path / "gap")
    cfg = json.loads((folder / "config.json").read_text())
    del cfg["inputs"], cfg["clip_norm"]
    (folder / "config.json").write_text(json.dumps(cfg))
    with pytest.raises(ModelError, match="lacks clip_norm, inputs"):  # never filled with today's defaults
        train.load(folder)


def test_a_classifier_built_directly_starts_with_the_papers_forget_bias():
    from study.learn.model import Classifier

    torch.manual_seed(0)
    mine = Classifier(3, hidden=8)
    torch.manual_seed(0)
    bare = Classifier(3, hidden=8, forget_bias=0.0)
    torch.testing.assert_close(_forget_biases(mine), _forget_biases(bare) + 1.0)


@pytest.mark.slow
def test_a_velocity_model_trains_saves_reloads_and_streams(ds, tmp_path):
    from study.learn.stream import Streamer

    cfg = dataclasses.replace(TINY, dims="z", inputs="velocity", epochs=2)
    tm = train.fit(ds, cfg, progress=False, warn=False)
    assert tm.net.features.n_channels == 2 and tm.net.features.fps == ds.fps
    back = train.load(tm.save(tmp_path / "v"))
    assert back.config.inputs == "velocity"
    np.testing.assert_array_equal(back.predict_proba(ds.test.x), tm.predict_proba(ds.test.x))
    s = Streamer(back.net)
    streamed = np.array([s.push(z) for z in ds.test.x[0, : tm.n_frames, 2:]])
    np.testing.assert_allclose(streamed, back.predict_proba_frames(ds.test.x[:1])[0], atol=1e-5)
    v = np.diff(ds.train.x[:, : tm.n_frames, 2], axis=1) * ds.fps
    assert float(tm.net.features.std[1]) == pytest.approx(float(np.concatenate([np.zeros((len(v), 1)), v], 1)[
        train.split_train_val(len(ds.train.y), cfg.val_fraction, cfg.seed)[0]].std()), rel=1e-4)


@pytest.mark.slow
def test_a_speed_model_trains_saves_reloads_and_streams_as_its_first_layer_reads(ds, tmp_path):
    from study.learn.stream import Streamer

    cfg = dataclasses.replace(TINY, inputs="speed", epochs=2)
    tm = train.fit(ds, cfg, progress=False, warn=False)
    assert tm.net.features.n_channels == 3
    back = train.load(tm.save(tmp_path / "s"))
    assert back.config.inputs == "speed"
    np.testing.assert_array_equal(back.predict_proba(ds.test.x), tm.predict_proba(ds.test.x))
    s = Streamer(back.net)
    streamed = np.array([s.push(f) for f in ds.test.x[0, : tm.n_frames]])
    np.testing.assert_allclose(streamed, back.predict_proba_frames(ds.test.x[:1])[0], atol=1e-5)
    tr = train.split_train_val(len(ds.train.y), cfg.val_fraction, cfg.seed)[0]
    v = np.diff(ds.train.x[tr, : tm.n_frames].astype(np.float64), axis=1) * ds.fps
    speed = np.concatenate([np.zeros((len(tr), 1)), np.hypot(v[..., 0], v[..., 1])], axis=1)
    assert float(tm.net.features.mean[2]) == pytest.approx(speed.mean(), rel=1e-4), "standardised on the training part"


def test_rotated_training_throws_are_turned_anew_every_epoch_and_seeded(ds):
    """Each epoch turns every training throw about the vertical by its own angle: the heights and the horizontal
    distances from the origin stay, the headings move; the draws are the run's own (seeded), the validation part is
    left as thrown."""
    T = 15
    tr, va = train.split_train_val(len(ds.train.y), 0.2, 0)
    cfg = dataclasses.replace(TINY, rotate=180.0)
    view, x_val = train.epoch_inputs(ds.train.x[:, :T], tr, va, cfg, ds.fps)
    plain, plain_val = train.epoch_inputs(ds.train.x[:, :T], tr, va, dataclasses.replace(cfg, rotate=0.0), ds.fps)
    np.testing.assert_array_equal(x_val, plain_val)
    exact = plain(0).numpy()
    e0, e1 = view(0).numpy(), view(1).numpy()
    assert view(1) is view(1), "an epoch draws once"
    for e in (e0, e1):
        np.testing.assert_array_equal(e[..., 2], exact[..., 2])
        np.testing.assert_allclose(np.hypot(e[..., 0], e[..., 1]), np.hypot(exact[..., 0], exact[..., 1]), atol=1e-6)
    heading = lambda a: np.arctan2(a[:, -1, 1], a[:, -1, 0])  # noqa: E731
    assert np.abs(np.angle(np.exp(1j * (heading(e0) - heading(exact))))).max() > 0.5, "turned"
    assert not np.allclose(e0, e1), "a new angle every epoch"
    again, _ = train.epoch_inputs(ds.train.x[:, :T], tr, va, cfg, ds.fps)
    np.testing.assert_array_equal(again(0).numpy(), e0)
    small, _ = train.epoch_inputs(ds.train.x[:, :T], tr, va, dataclasses.replace(cfg, rotate=10.0), ds.fps)
    turn = np.abs(np.angle(np.exp(1j * (heading(small(0).numpy()) - heading(exact)))))
    assert turn.max() <= np.radians(10.0) + 1e-5, "within [-rotate, rotate] degrees"


def test_fixed_observation_training_draws_anew_every_epoch_and_is_seeded(ds):
    """Frozen weights and no dropout: an epoch's training loss is the loss of the whole training part (up to the
    order of the sum), so it changes from epoch to epoch only if the positions do."""
    cfg = dataclasses.replace(FROZEN, observe="fixed", observe_noise=0.05, dropout=0.0, epochs=3, patience=3)
    a = train.fit(ds, cfg, progress=False, warn=False)
    b = train.fit(ds, cfg, progress=False, warn=False)
    assert a.history == b.history, "seeded"
    exact = train.fit(ds, dataclasses.replace(cfg, observe="exact"), progress=False, warn=False)
    still = [h["train_loss"] for h in exact.history]
    drawn = [h["train_loss"] for h in a.history]
    assert max(still) - min(still) < 1e-6 < min(abs(x - y) for x, y in zip(drawn, drawn[1:]))
    assert exact.history[0]["val_loss"] != a.history[0]["val_loss"], "validation observed too"


def test_randomised_observation_training_sees_other_positions_than_exact(ds):
    cfg = dataclasses.replace(FROZEN, observe="randomised", observe_noise=0.01, observe_drop=0.1, epochs=2)
    tm = train.fit(ds, cfg, progress=False, warn=False)
    exact = train.fit(ds, dataclasses.replace(cfg, observe="exact"), progress=False, warn=False)
    again = train.fit(ds, cfg, progress=False, warn=False)
    assert tm.config.observe == "randomised" and np.isfinite(tm.history[0]["val_loss"])
    assert tm.history != exact.history, "trained and validated on observed positions, not the exact ones"
    assert tm.history == again.history, "seeded: the same observations every time"
    with pytest.raises(ConfigError, match="observe"):
        train.fit(ds, dataclasses.replace(cfg, observe="blurred"), progress=False)


def test_any_camera_training_sees_heights_only_and_is_seeded(ds, tmp_path):
    cfg = dataclasses.replace(FROZEN, dims="z", observe="any-camera", observe_noise=0.01, epochs=2)
    tm = train.fit(ds, cfg, progress=False, warn=False)
    randomised = train.fit(ds, dataclasses.replace(cfg, observe="randomised"), progress=False, warn=False)
    assert tm.history == train.fit(ds, cfg, progress=False, warn=False).history, "seeded"
    assert tm.history != randomised.history and np.isfinite(tm.history[-1]["val_loss"])
    assert train.load(tm.save(tmp_path / "m")).config.observe == "any-camera"


def test_a_network_trained_at_every_frame_answers_at_every_frame_and_streams(ds):
    from study.learn.stream import Streamer

    cfg = dataclasses.replace(TINY, dims="z", loss_at="every", epochs=2)
    tm = train.fit(ds, cfg, progress=False)
    frames = tm.predict_proba_frames(ds.test.x)
    assert frames.shape == (len(ds.test.y), tm.n_frames, 2)
    np.testing.assert_allclose(frames[:, -1], tm.predict_proba(ds.test.x), atol=1e-6)  # the last frame is the answer
    s = Streamer(tm.net)
    streamed = np.array([s.push(z) for z in ds.test.x[0, : tm.n_frames, 2:]])
    np.testing.assert_allclose(streamed, frames[0], atol=1e-5)  # what a car would run, frame by frame
    with pytest.raises(ConfigError, match="loss_at"):
        train.fit(ds, dataclasses.replace(cfg, loss_at="first"), progress=False)


def test_a_failure_verdict_fits_its_evidence():
    """Judged on the validation loss as well as the accuracy; a validation part too small to tell says so."""
    from study.learn.metrics import PLATEAU_LOSS, too_few_to_tell, training_state

    assert too_few_to_tell(3) and not too_few_to_tell(4), "3 right of 3 is within a coin's reach; 4 of 4 is not"
    assert training_state(1.0, 0.001, 3) == "too few to tell", "3 of 3 right at a loss of 0.001: not a failure"
    assert training_state(1.0, 0.69, 3) == "failed", "a coin's loss fails whatever the split"
    assert training_state(0.52, 0.40, 400) == "failed", "at chance on enough throws: failed, however low the loss"
    assert training_state(0.80, 0.40, 400) == "trained"
    assert training_state(0.80, float("nan"), 400) == "failed" and training_state(0.80, PLATEAU_LOSS, 400) == "failed"
    from study.learn.model import Classifier

    net = Classifier(1)
    hist = [{"epoch": 0, "train_loss": 0.1, "val_loss": 0.001, "val_accuracy": 1.0}]
    tm = train.TrainedModel(net, train.TrainConfig(), 30.0, history=hist, n_val=3)
    assert not tm.failed and tm.training_state == "too few to tell"
    msg = tm.failure()
    assert "too small to tell" in msg and "never left" not in msg and "3 of 3" in msg
    plateau = train.TrainedModel(net, train.TrainConfig(), 30.0, n_val=3,
                                 history=[{"epoch": 0, "train_loss": 0.7, "val_loss": 0.69, "val_accuracy": 0.67}])
    assert plateau.failed and "never left the initial plateau" in plateau.failure()
    chance = train.TrainedModel(net, train.TrainConfig(), 30.0, n_val=400,
                                history=[{"epoch": 0, "train_loss": 0.5, "val_loss": 0.5, "val_accuracy": 0.51}])
    assert chance.failed and "cannot be told from guessing" in chance.failure()
    assert "another seed, a lower lr" in chance.failure() and "--seed" not in chance.failure(), "Python: the fields"
    assert "another --seed, a lower --lr" in chance.failure("cli"), "the command line: its options"
    assert chance.failure("none").endswith("(its loss 0.500)"), "no advice where the caller gives its own"
    with pytest.raises(ValueError, match="advice"):
        chance.failure("gui")


def test_a_cosine_budget_warms_up_then_falls_to_its_floor():
    cfg = TrainConfig(lr=2e-3, lr_schedule="cosine", warmup_epochs=4, epochs=24, lr_floor=0.05)
    rates = [cfg.lr_at(e) for e in range(cfg.epochs)]
    assert rates[:4] == pytest.approx([5e-4, 1e-3, 1.5e-3, 2e-3]), "linear warm-up to the rate"
    assert rates[-1] == pytest.approx(1e-4) and all(a >= b for a, b in zip(rates[4:], rates[5:])), "down to 5 %"
    assert not cfg.stops_early and TrainConfig().stops_early and TrainConfig().lr_at(3) is None
    short = TrainConfig(lr=1e-3, lr_schedule="cosine", warmup_epochs=5, epochs=3, lr_floor=0.1)
    assert [short.lr_at(e) for e in range(3)] == pytest.approx([5e-4, 1e-3, 1e-4]), "a short budget warms up less"


@pytest.mark.parametrize("changes, field", [({"warmup_epochs": -1}, "warmup_epochs"), ({"lr_floor": 0.0}, "lr_floor"),
                                            ({"ema_decay": 1.0}, "ema_decay"), ({"average": "swa"}, "average")])
def test_recipe_fields_out_of_range_name_themselves(changes, field):
    with pytest.raises(ConfigError, match=f"TrainConfig.{field}"):
        dataclasses.replace(TrainConfig(), **changes).check()


@pytest.mark.slow  # two tiny runs
def test_the_torch_lstm_trains_on_a_cosine_budget_and_keeps_its_average(smoke_dataset):
    cfg = TrainConfig(cell="torch-lstm", length=1.0, epochs=3, truncation=10, lr_schedule="cosine",
                      average="ema", ema_decay=0.5)
    tm = train.fit(smoke_dataset, cfg, warn=False)
    assert len(tm.history) == 3 and [h["lr"] for h in tm.history] == [cfg.lr_at(e) for e in range(3)]
    plain = train.fit(smoke_dataset, dataclasses.replace(cfg, average="none"), warn=False)
    kept = [p for p in tm.net.parameters()]
    assert any(not torch.equal(a, b) for a, b in zip(kept, plain.net.parameters())), "the average is what is kept"


def test_an_ensemble_is_the_mean_of_its_members_probabilities(ds, tm):
    from study.learn.trained import Ensemble

    other = train.fit(ds, dataclasses.replace(TINY, seed=1), progress=False)
    x = ds.test.x
    both = Ensemble((tm, other))
    assert (both.dims, both.n_frames, both.fps) == (tm.dims, tm.n_frames, tm.fps)
    np.testing.assert_array_equal(both.predict_proba(x), (tm.predict_proba(x) + other.predict_proba(x)) / 2)
    np.testing.assert_array_equal(Ensemble((tm,)).predict_proba(x), tm.predict_proba(x))
    with pytest.raises(ConfigError, match="empty"):
        Ensemble(())
    z = train.fit(ds, dataclasses.replace(TINY, dims="z"), progress=False)
    with pytest.raises(ConfigError, match="different inputs"):
        Ensemble((tm, z))


def test_the_weights_average_warms_up_to_its_decay():
    cfg = TrainConfig()
    decays = [cfg.ema_decay_at(t) for t in range(0, 20000, 7)]
    assert cfg.ema_decay_at(0) == pytest.approx(0.1) and decays[-1] == cfg.ema_decay == 0.999
    assert all(a <= b for a, b in zip(decays, decays[1:])), "it only ever remembers longer"
    assert cfg.ema_decay_at(90) <= 0.91, "a run of a hundred steps is not held at its initial weights"


def test_a_saved_model_folder_follows_the_umask(tm, tmp_path):
    import os
    old = os.umask(0o022)
    try:
        out = tm.save(tmp_path / "m")
        assert out.stat().st_mode & 0o777 == 0o755  # 0o700 before: tempfile.mkdtemp's, whatever the umask
        assert (out / "weights.pt").stat().st_mode & 0o777 == 0o644
    finally:
        os.umask(old)


def test_halving_check_ranks_points_by_the_pick_rule_on_each_histories_prefix():
    import scripts_toys

    script = scripts_toys.script("scripts/halving_check.py")

    def run(accs):  # validation loss falls whenever accuracy rises
        return [{"val_accuracy": a, "val_loss": 1.0 - a} for a in accs]

    late = [run([0.6] * 30 + [0.9] * 30)] * 3  # the late starter: behind at 20 epochs, ahead at the end
    early = [run([0.7] * 60)] * 3
    points = {(1e-3, 90): late, (1e-3, 30): early}
    assert script.pick(points, None)[0] == (1e-3, 90)
    assert script.pick(points, 20)[0] == (1e-3, 30), "a rung at 20 epochs would drop the full grid's pick"
