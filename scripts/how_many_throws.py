"""How many throws a class the study's protocol needs before it trains: the number ``study train`` quotes when a run
on a small data set fails.

For each size, a data set of the smoke preset's 3-second throws with that many training throws a class (and 50
test throws a class), and the protocol (``study.TrainConfig()``'s defaults) trained with three seeds; one line a
run: size, seed, whether it trained (``TrainedModel.training_state``), its validation accuracy and size, its test
accuracy, epochs, seconds. Minutes on two cores::

    .venv/bin/python scripts/how_many_throws.py --sizes 8 25 50 100 200 --data-dir ~/study-need
"""

from __future__ import annotations

import argparse
import time

import study


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[8, 25, 50, 100, 200], help="training throws a class")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="network seeds per size")
    ap.add_argument("--data-dir", default=None, help="cache folder for the data sets (default: data/)")
    a = ap.parse_args()
    print("per_class seed state val_accuracy n_val test_accuracy epochs seconds")
    for n in a.sizes:
        cfg = study.SynthConfig.preset("smoke").replace(n_train=n, n_test=50)
        ds = study.dataset(cfg, seed=0, data_dir=a.data_dir, progress=False)
        for seed in a.seeds:
            t = time.time()
            m = study.fit(ds, study.TrainConfig(seed=seed), progress=False, warn=False)
            acc = study.evaluate(m, ds.test)["accuracy"]
            print(n, seed, m.training_state, f"{m.val_accuracy:.3f}", m.n_val, f"{acc:.3f}", len(m.history),
                  f"{time.time() - t:.0f}", flush=True)


if __name__ == "__main__":
    main()
