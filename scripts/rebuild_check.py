"""Does a rebuild agree? Table 1 trained again on another time loop or another data seed, as a results file.

The book's Table 1 comes from one machine, one time loop (the compiled one, where a compiler exists)
and one data seed. This script trains Table 1's runs again at the same configuration (read from a
build's results file) with the PyTorch time loop instead of the compiled one (``--backend torch``), or
on a dataset simulated from another seed (``--data-seed 1``), and writes the mean of the seeds under the book's
names, beside the run validation picks on that one data set (``table1.<dims>.validation_pick``: the book's
statistic, ``study.runs.stats.validation_pick``, over one data set instead of the book's several).
With ``--light-priors balls`` it trains them on the study's first light prior (balls'
masses and restitutions, ``study.simulate.synth.LIGHT_BALLS``) instead of the box-like one. Then

    study results _build/results.json --compare table1-torch.json

lists the numbers that moved outside each other's 95 % intervals. ``--seeds 3`` trains the first three
seeds only, for a check that costs 60 % of Table 1's training.

    python scripts/rebuild_check.py --results _build/results.json --backend torch --out table1-torch.json
    python scripts/rebuild_check.py --results _build/results.json --data-seed 1 --out table1-seed1.json
    python scripts/rebuild_check.py --results _build/results.json --light-priors balls --out table1-balls.json

With ``--chapters table1 decision ...`` it re-executes whole chapters of the book instead, the chapters
themselves (no copy of their logic), on the PyTorch time loops (``--backend torch``), in a scratch book that
shares the project's data folder: its data sets, videos and calibration are reused, while every training run
has another key (the time loop is part of it) and is trained again. The chapters' numbers, every headline
the summary page quotes from them included, land in ``--out``:

    python scripts/rebuild_check.py --chapters table1 decision --backend torch --out torch.json
    study results _build/results.json --compare torch.json --all
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--results", type=Path, default=Path("_build/results.json"), help="the build whose Table 1 to redo")
    ap.add_argument("--backend", choices=("native", "torch"), default="native", help="time loop of the new runs")
    ap.add_argument("--data-seed", type=int, default=0, help="seed of the dataset the new runs train on")
    ap.add_argument("--light-priors", choices=("box", "balls"), default="box", help="the light class's priors")
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--data-dir", type=Path, default=Path("data"))
    ap.add_argument("--seeds", type=int, default=0, help="train only the first N of the preset's seeds (0: all)")
    ap.add_argument("--workers", type=int, default=0, help="training processes (0: one per CPU)")
    ap.add_argument("--out", type=Path, required=True, help="results file to write")
    ap.add_argument("--chapters", nargs="+", metavar="CHAPTER", default=None,
                    help="re-execute these chapters of the book (file stems) instead of Table 1's runs alone")
    a = ap.parse_args(argv)
    if a.backend == "torch":
        os.environ["STUDY_NATIVE"] = "0"  # before study.learn.native is imported, here and in the workers
    if a.chapters:
        return chapters(a.chapters, a.preset, a.data_dir, a.out)

    import dataclasses

    from study.book import results
    from study.learn.train import TrainConfig
    from study.report.reported import count, number
    from study.report.text import fmt
    from study.runs import Runner, preset, stats
    from study.simulate import synth

    source = results.load(a.results)["table1.z.mean"].source
    cfg = TrainConfig(**source["config"])
    p = preset(a.preset)
    if a.seeds:
        p = dataclasses.replace(p, seeds=p.seeds[:a.seeds])
    synth_cfg = synth.SynthConfig.preset(a.preset)
    if a.light_priors == "balls":
        synth_cfg = synth_cfg.replace(light=synth.LIGHT_BALLS)
    ds = synth.dataset(synth_cfg, seed=a.data_seed, data_dir=a.data_dir)
    runs = Runner(ds, p, a.data_dir.resolve(), workers=a.workers, progress=True).seed_runs(cfg)
    leaves = []
    for d in ("xyz", "z"):
        these = runs.where(dims=d)
        pick = stats.validation_pick([these])  # the book's statistic, over this one data set
        s = stats.summary(these)
        leaves += [(f"table1.{d}.validation_pick", number(pick.interval, f"the run validation picks, {d}",
                                                          seed=pick.picked[0].seed)),
                   (f"table1.{d}.mean", number(s.interval, f"mean over seeds, {d}", config=dataclasses.asdict(cfg))),
                   (f"table1.{d}.failed", count(s.failed, "seeds that failed to train"))]
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(results.dumps(leaves, preset=f"{a.preset} (backend {a.backend}, data seed {a.data_seed}, "
                                                  f"light priors {a.light_priors})"))
    for name, n in results.load(a.out).items():
        print(f"{name}: {fmt(n)}")
    print(f"written: {a.out}", file=sys.stderr)
    return 0


def chapters(stems: list[str], preset: str, data_dir: Path, out: Path) -> int:
    """Execute the book's chapters ``stems`` in a scratch book beside the project (its own _build, the project's
    data folder) and write their merged results to ``out``."""
    import shutil

    from study.book import builder

    root = Path(__file__).resolve().parents[1]
    known = [c.stem for c in builder.chapters(root)]
    unknown = [s for s in stems if s not in known]
    if unknown:
        print(f"rebuild_check: no chapter {', '.join(unknown)}; the chapters are {', '.join(known)}", file=sys.stderr)
        return 2
    clips = root.parent / "shared" / "data" / "real-video"  # the real-world chapter's clips, read where they lie
    if clips.is_dir():
        os.environ.setdefault("STUDY_REAL_VIDEO", str(clips))
    with tempfile.TemporaryDirectory(prefix="rebuild-check-") as tmp:
        scratch = Path(tmp)
        for name in ("book", "src", "_config.yml", "references.bib"):
            (scratch / name).symlink_to(root / name)
        data_dir.mkdir(parents=True, exist_ok=True)
        (scratch / "data").symlink_to(data_dir.resolve())
        (scratch / "_toc.yml").write_text("format: jb-book\nroot: book/" + stems[0] + "\n"
                                          + ("chapters:\n" + "".join(f"  - file: book/{s}\n" for s in stems[1:])
                                             if stems[1:] else ""))
        builder.execute(scratch, preset)
        out.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(scratch / "_build" / "results.json", out)
    print(f"written: {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
