"""The dataset file format: round trip, and a clear DataError for every kind of bad file."""

import numpy as np
import pytest

from study.core.errors import DataError
from study.simulate import data


def toy_dataset(n: int = 4, T: int = 10) -> data.Dataset:
    rng = np.random.default_rng(0)
    split = lambda: data.Split(  # noqa: E731
        x=rng.normal(size=(n, T, 3)).astype(np.float32),
        y=np.arange(n) % 2,
        params={"mass": rng.uniform(size=n)},
    )
    return data.Dataset(train=split(), test=split(), fps=30.0, meta={"key": "abc"})


def test_round_trip_is_bitwise(tmp_path):
    ds = toy_dataset()
    path = data.save(ds, tmp_path / "d.npz")
    back = data.load(path)
    assert back.key == "abc" and back.fps == 30.0 and back.n_frames == 10
    for name in data.SPLITS:
        a, b = ds.split(name), back.split(name)
        assert a.x.tobytes() == b.x.tobytes() and np.array_equal(a.y, b.y)
        assert a.params["mass"].tobytes() == b.params["mass"].tobytes()
    assert not list(tmp_path.glob(".*tmp")), "no temporary file is left behind"


def test_missing_file(tmp_path):
    with pytest.raises(DataError, match="no such file"):
        data.load(tmp_path / "nope.npz")


def test_empty_file(tmp_path):
    (tmp_path / "e.npz").write_bytes(b"")
    with pytest.raises(DataError, match="empty"):
        data.load(tmp_path / "e.npz")


def test_truncated_file(tmp_path):
    path = data.save(toy_dataset(), tmp_path / "d.npz")
    raw = path.read_bytes()
    path.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(DataError, match="cannot be read"):
        data.load(path)


def test_edited_array_fails_checksum(tmp_path):
    ds = toy_dataset()
    path = data.save(ds, tmp_path / "d.npz")
    with np.load(path) as z:
        arrays = dict(z)
    arrays["train/x"] = arrays["train/x"] + 1
    np.savez(path, **arrays)
    with pytest.raises(DataError, match="checksum"):
        data.load(path)


def test_not_a_dataset(tmp_path):
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(DataError, match="not a study dataset"):
        data.load(tmp_path / "other.npz")


def test_a_csv_given_as_a_dataset_is_named_for_what_it_is(tmp_path):
    (tmp_path / "mine.csv").write_text("t,x,y,z\n0,0,0,0.1\n")
    with pytest.raises(DataError, match="mine.csv: a text file, not a data set.*study classify CSV") as e:
        data.load(tmp_path / "mine.csv")
    assert "delete it and rebuild" not in str(e.value)  # a cache file's advice, which it said before


def test_written_files_follow_the_umask(tmp_path):
    import os
    old = os.umask(0o022)
    try:
        path = data.save(toy_dataset(), tmp_path / "d.npz")
        assert path.stat().st_mode & 0o777 == 0o644  # 0o600 before: tempfile's mode, whatever the umask
        os.umask(0o077)
        assert data.save(toy_dataset(), tmp_path / "e.npz").stat().st_mode & 0o777 == 0o600
    finally:
        os.umask(old)
