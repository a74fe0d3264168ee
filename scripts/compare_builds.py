"""Are two builds the same? Every number of their results files and every run record, compared value by value.

``study results A --compare B`` asks whether numbers moved outside each other's intervals; this asks whether
they are *identical*, as they must be after a change that only moves code (a refactor changes every cache
key, so the runs are trained again and must come out the same bit for bit). For two project roots that
each hold a built book (``_build/results.json``) and its caches (``data/``, or the folders ``--data`` names for
builds made with ``study book --data-dir``):

- every number and verdict present in either results file (of either format; the first format's names read
  under today's, ``study.book.results.RENAMED``): value, interval, method, unit, paper value, verdict, the
  inputs it was decided from, and description equal; of its source, everything but the dataset key (which
  hashes the simulation's code); timings (names with ``time.``, the sweep's render CPU time) are skipped;
- every run record of either ``data/runs/``, paired with the other build's record of the same run (the same
  training config, the same test flag, on a dataset with the same config and seed, or, for a dataset with no
  file of its own, the same config and test split size): equal in everything but its key, its dataset key and
  its training time.

    python scripts/compare_builds.py /path/to/before /path/to/after [--data BEFORE_CACHE AFTER_CACHE]

Exit status 0 when everything compared is identical, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from study.book import results
from study.learn.config import RENAMED as CONFIG_RENAMED
from study.report.reported import Number

SOURCE_DATASET_KEYS = ("data_key", "data")
"""Names under which a number's source gives the key of a data set (which hashes the simulation's code): skipped."""
TIMING = ("time.", "render_cpu_s")
"""Names of numbers that are times (wall clock or CPU): skipped, never compared."""
RECORD_SKIP = ("key", "data_key", "train_seconds", "cpu_seconds")
"""Fields of a run record that hash code or time it, not what it computed."""


def _canon(obj) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"))


def _today(obj):
    """``obj`` with every training config's fields under today's names (``max_epochs`` -> ``epochs``:
    ``study.learn.config.RENAMED``), so that a build from before a rename pairs with one after it."""
    if isinstance(obj, dict):
        return {k: (_renamed_config(v) if k == "config" and isinstance(v, dict) else _today(v)) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_today(v) for v in obj]
    return obj


def _renamed_config(cfg: dict) -> dict:
    return {CONFIG_RENAMED.get(k, k): _today(v) for k, v in cfg.items()}


def dataset_identity(data_dir: Path, key: str) -> str | None:
    """The config and seed a dataset was simulated from, as canonical JSON; None without a file."""
    for pattern in (f"synth-{key}.npz", f"*-{key}.npz"):
        for path in data_dir.glob(pattern):
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(z["__meta__"].tobytes().decode())
            if "config" in meta:
                return _canon({"config": meta["config"], "seed": meta["seed"]})
    return None


def records(data_dir: Path) -> dict[str, list[dict]]:
    """Every run record of ``data_dir/runs`` (a build's cache folder), grouped by what run it is (see the module
    docstring)."""
    identities: dict[str, str | None] = {}
    out: dict[str, list[dict]] = defaultdict(list)
    for f in sorted((data_dir / "runs").glob("*.json")):
        rec = _today(json.loads(f.read_text()))
        k = rec["data_key"]
        if k not in identities:
            identities[k] = dataset_identity(data_dir, k)
        n_test = len(rec["test"]["p_heavy"]) if rec.get("test") else None
        ident = identities[k] or f"unfiled dataset, {rec.get('n_val')} validation throws"
        out[_canon({"data": ident, "config": rec["config"], "test": n_test})].append(rec)
    return out


def _leaf(leaf) -> dict:
    """What a results file says of one number or verdict, in either format: everything but how it is displayed
    (``signed``) and the dataset key its source names (which hashes the simulation's code)."""
    out = {"what": leaf.what, "verdict": leaf.verdict,
           "decision": None if leaf.decision is None else leaf.decision.inputs,
           "source": _today({k: v for k, v in leaf.source.items() if k not in SOURCE_DATASET_KEYS})}
    if isinstance(leaf, Number):
        out.update(value=leaf.value, lo=leaf.lo, hi=leaf.hi, method=leaf.method, unit=leaf.unit, paper=leaf.paper)
    return json.loads(_canon(out))


def compare_results(a: Path, b: Path) -> tuple[int, int, list[str]]:
    """(numbers and verdicts compared, those that differ, messages). Either file may be of either results format;
    a file of the first is read under today's names (``study.book.results.RENAMED``)."""
    A, B = results.load(a), results.load(b)
    msgs, compared, differ = [], 0, 0
    for name in sorted(set(A) | set(B)):
        if name not in A or name not in B:
            msgs.append(f"only in {'the first' if name in A else 'the second'}: {name}")
            differ += 1
            continue
        if any(t in name for t in TIMING):
            continue
        x, y = _leaf(A[name]), _leaf(B[name])
        compared += 1
        if x != y:
            differ += 1
            diff = {k: (x.get(k), y.get(k)) for k in x if x.get(k) != y.get(k)}
            msgs.append(f"differs: {name}: {diff}")
    return compared, differ, msgs


def compare_records(a: Path, b: Path) -> tuple[int, int, list[str]]:
    """(records compared, records that differ or have no counterpart, messages) of two cache folders."""
    A, B = records(a), records(b)
    msgs, compared, differ = [], 0, 0
    strip = lambda r, *more: _canon({k: v for k, v in r.items() if k not in RECORD_SKIP + more})  # noqa: E731
    for ident in sorted(set(A) | set(B)):
        xs, ys = A.get(ident, []), B.get(ident, [])
        if not xs or not ys:  # a validation-only record is implied by the same run scored on the test split
            have, side = (xs, B) if xs else (ys, A)
            if json.loads(ident)["test"] is None:
                scored = [r for k, rs in side.items() if json.loads(k)["config"] == json.loads(ident)["config"]
                          and json.loads(k)["data"] == json.loads(ident)["data"] for r in rs]
                if scored and sorted(strip(r, "test") for r in have) == sorted(strip(r, "test") for r in scored[:1]):
                    continue
        sx, sy = sorted(map(strip, xs)), sorted(map(strip, ys))
        compared += max(len(xs), len(ys))
        if sx != sy:
            differ += max(len(xs), len(ys))
            cfg = json.loads(ident)["config"]
            msgs.append(f"run differs or is missing ({len(xs)} vs {len(ys)} records): cell {cfg['cell']}, dims "
                        f"{cfg['dims']}, length {cfg['length']}, seed {cfg['seed']}")
    return compared, differ, msgs


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("first", type=Path, help="a project root with _build/results.json and data/")
    ap.add_argument("second", type=Path, help="another")
    ap.add_argument("--data", type=Path, nargs=2, metavar=("FIRST_DATA", "SECOND_DATA"),
                    help="the two builds' cache folders, where they were built with --data-dir (default: each root's data/)")
    a = ap.parse_args(argv)
    n_num, d_num, m_num = compare_results(a.first / "_build" / "results.json", a.second / "_build" / "results.json")
    first_data, second_data = a.data or (a.first / "data", a.second / "data")
    n_rec, d_rec, m_rec = compare_records(first_data, second_data)
    for m in m_num + m_rec:
        print(m)
    print(f"numbers: {n_num} compared (timings aside), {d_num} differ; "
          f"run records: {n_rec} compared, {d_rec} differ or have no counterpart", file=sys.stderr)
    return 0 if d_num == d_rec == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
