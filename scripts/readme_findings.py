"""The README's findings, from a paper build's results: the summary chapter's findings paragraph and a small table
(Table 1 beside the paper, what the motion allows, the real-world test, a user's camera), labelled with the commit
the build was made from. Prints the block; with ``--write README.md``, replaces the block between the README's
markers (nothing else of the file changes)::

    .venv/bin/python scripts/readme_findings.py _build/results.json --commit "$(git rev-parse --short HEAD)" \\
        --write README.md
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from study.book import results, summary
from study.report.reported import Number

BEGIN = "<!-- findings: begin -->"
END = "<!-- findings: end -->"
RECIPE_KIND = "positions-any-camera"
"""The kind of model the README's own-trajectories recipe trains for video (``study.runs.measured.kind``)."""


def _pct(n: Number | None) -> str:
    if n is None:
        return "not in this build"
    return f"{100 * n.value:.1f} % [{100 * n.lo:.1f}, {100 * n.hi:.1f}]"


def block(path: Path, commit: str) -> str:
    """The README's findings block (markers included) from the results file at ``path``."""
    got = results.load(path)
    preset = str(json.loads(Path(path).read_text()).get("preset", "paper"))
    page = summary.compute(path, preset)

    def num(name: str) -> Number | None:
        n = got.get(name)
        return n if isinstance(n, Number) else None

    def verdict(name: str) -> str:
        n = num(name)
        return f"**{n.verdict}**" if n is not None and n.verdict else ""

    def unsettled(dims: str) -> str:
        n = num(f"table1.{dims}.unsettled_picks")
        return "" if n is None or not n.value else f" ({n.value:.0f} of the runs validation picks not settled)"

    rows = [
        ("Table 1, X, Y, Z", "81 %", _pct(num("table1.xyz.paper_way")) + unsettled("xyz"),
         verdict("table1.xyz.paper_way")),
        ("Table 1, Z only", "78 %", _pct(num("table1.z.paper_way")) + unsettled("z"), verdict("table1.z.paper_way")),
    ]
    on, off = num("motion.ceiling.air_on"), num("motion.ceiling.air_off")
    if on is not None and off is not None:
        rows.append(("best any classifier can do (exact, from the priors): with air / without", "—",
                     f"{100 * on.value:.1f} % / {100 * off.value:.1f} %", ""))
    for c, paper in (("light", "93 %"), ("heavy", "100 %")):
        rows.append((f"real-world test, rendered {c} videos (Table 1's Z model)", paper,
                     _pct(num(f"realworld.table1.rendered.{c}")), verdict(f"realworld.table1.rendered.{c}")))
    rows.append(("real clips of tennis balls (light; others' footage)", "93 % (golf ball)",
                 _pct(num("realworld.table1.real.light")), verdict("realworld.table1.real.light")))
    sweep, exact = num("usercamera.sweep.all.mean.accuracy"), num("usercamera.sweep.all.exact.accuracy")
    if sweep is not None and exact is not None:
        rows.append(("80 clips from cameras nobody measured (recommended model; exact heights → a user's path)", "—",
                     f"{_pct(exact)} → {_pct(sweep)}", ""))
    recipe = [num(f"usercamera.sweep.kind.{RECIPE_KIND}.{path}") for path in ("exact", "mean", "floor")]
    if recipe[0] is not None and recipe[1] is not None:
        rows.append(("the same clips, a model like the recipe's below (`observe=\"any-camera\"`; exact heights → one "
                     "scale → floor marks, over the clips each path gave heights for)", "—",
                     " → ".join(_pct(n) for n in recipe), ""))
    table = ["| | the paper | ours [95 % CI] | verdict |", "|---|---|---|---|"]
    table += [f"| {a} | {b} | {c} | {d} |" for a, b, c, d in rows]
    return "\n".join([BEGIN, f"**What the study found** (the `{page.preset}` preset's build of commit `{commit}`; "
                      f"every number is in that build's `_build/results.json`). {page.findings}", "",
                      *table, END])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", type=Path, help="a paper build's _build/results.json")
    ap.add_argument("--commit", required=True, help="the commit the build was made from")
    ap.add_argument("--write", type=Path, default=None, metavar="README", help="replace the block in this file")
    a = ap.parse_args(argv)
    text = block(a.results, a.commit)
    if a.write is None:
        print(text)
        return 0
    old = a.write.read_text() if a.write.is_file() else ""
    if BEGIN not in old or END not in old:
        print(f"readme_findings: {a.write} has no {BEGIN} ... {END} block to replace", file=sys.stderr)
        return 2
    a.write.write_text(re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda _: text, old, flags=re.S))
    return 0


if __name__ == "__main__":
    sys.exit(main())
