"""The package's shipped copy of what a paper build's camera sweep measured (``study.runs.measured.SHIPPED``):
each kind of model's accuracy through each path, so that ``study classify`` in a clone that has built no book
still says how far to trust an answer. Regenerated from a paper build's results, as the README's findings are::

    .venv/bin/python scripts/shipped_measured.py _build/results.json --commit "$(git rev-parse --short HEAD)" --write

Prints what it would write; ``--write`` writes it.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from study.book import results
from study.report.usercamera import measured as sweep_measured
from study.runs import measured


def shipped(path: Path, commit: str) -> measured.Shipped:
    """The shipped copy from the results file at ``path`` (a paper build's: refused otherwise)."""
    preset = str(json.loads(Path(path).read_text()).get("preset", ""))
    if preset != "paper":
        raise SystemExit(f"{path}: a {preset!r} build; the shipped copy comes from a paper build's results")
    leaves = results.load(path)
    got = sweep_measured(leaves)
    if not got:
        raise SystemExit(f"{path}: no usercamera.sweep.kind.* numbers (built before the sweep kept them)")
    return measured.Shipped(commit, preset, int(leaves["usercamera.sweep.all.clips"].value), got)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", type=Path, help="a paper build's _build/results.json")
    ap.add_argument("--commit", required=True, help="the commit that build was made from")
    ap.add_argument("--write", action="store_true", help=f"write {measured.SHIPPED}")
    a = ap.parse_args(argv)
    got = shipped(a.results, a.commit)
    if a.write:
        print(f"wrote {measured.write_shipped(measured.SHIPPED, got)}")
    else:
        for kind, by_path in got.measured.items():
            print(kind, {p: round(iv.value, 3) for p, iv in by_path.items()})
    return 0


if __name__ == "__main__":
    sys.exit(main())
