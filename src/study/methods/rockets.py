"""MiniRocket fits, cached by content like training runs: the practitioner's baseline costs one fit per build.

A fit's record holds its p(heavy) on each named test input it was asked about (``MiniRocket.p_heavy``: above 1/2
where it labels heavy), in
``data_dir/rocket/<key>.json``; the key hashes the dataset's key, the training inputs (the training split,
or an observed copy of it), the dims, the input length, the seed, every test input's bytes, the code of
``study.learn.rocket`` and the versions of sktime and scikit-learn. It is written atomically.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from study.core import cache
from study.learn.config import Dims
from study.learn.rocket import MiniRocket
from study.simulate.data import Dataset

FORMAT = "study.rocket/2"


def rocket_key(dataset: Dataset, dims: Dims, n_frames: int, seed: int, tests: dict[str, np.ndarray],
               train_x: np.ndarray | None = None) -> str:
    """The cache key of one MiniRocket fit and its predictions on ``tests``."""
    import sklearn
    import sktime

    return cache.key({
        "format": FORMAT, "data": dataset.key, "dims": dims, "n_frames": n_frames, "seed": seed,
        "train": None if train_x is None else cache.array_checksum({"x": np.asarray(train_x)}),
        "tests": {name: cache.array_checksum({"x": np.asarray(x)}) for name, x in sorted(tests.items())},
        "code": cache.code_hash("minirocket"), "sktime": sktime.__version__,
        "sklearn": sklearn.__version__,
    })


def rocket_predictions(dataset: Dataset, dims: Dims, n_frames: int, seed: int, tests: dict[str, np.ndarray],
                       data_dir: str | Path, train_x: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """MiniRocket on the first ``n_frames`` frames of ``dims``, fitted on the training split (or on ``train_x``,
    (n, T, 3) metres, the same throws observed), seeded: its p(heavy) (n,) float64 on each test input of ``tests``
    (name -> (n, T, 3) metres), above 1/2 where it labels heavy. Read from the cache when this very fit was made
    before."""
    key = rocket_key(dataset, dims, n_frames, seed, tests, train_x)
    path = Path(data_dir) / "rocket" / f"{key}.json"
    try:
        record = json.loads(path.read_text())
        if record.get("key") == key and set(record["predictions"]) == set(tests):
            return {k: np.asarray(v, dtype=np.float64) for k, v in record["predictions"].items()}
    except (OSError, ValueError, KeyError, TypeError):
        pass  # not fitted yet, or damaged: fit again
    model = MiniRocket(dims=dims, n_frames=n_frames, seed=seed)
    model.fit(dataset.train.x if train_x is None else train_x, dataset.train.y)
    predictions = {name: model.p_heavy(x) for name, x in tests.items()}
    body = {"key": key, "format": FORMAT, "predictions": {k: v.tolist() for k, v in predictions.items()}}
    cache.write_text_atomic(path, json.dumps(body) + "\n")
    return predictions
