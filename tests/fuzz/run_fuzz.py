"""The full fuzz run: ``python tests/fuzz/run_fuzz.py [--cases N] [--seed S] [--out DIR]``.

Draws at least N cases (default 10,000) from :mod:`cases`, runs them through the CLI
(:mod:`runner`) and prints a table of outcomes by family; every case that was not clean is
listed with its arguments and what it did, and its folder is kept under ``DIR`` (default
a temporary folder) to reproduce it. Exit 0 when every case was clean.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from cases import FAMILIES, cases  # noqa: E402
from runner import OUTCOMES, run_cases  # noqa: E402


def table(results) -> list[str]:
    counts = Counter((r.case.family, r.outcome) for r in results)
    lines = ["| family | cases | " + " | ".join(OUTCOMES) + " |",
             "|---|---|" + "---|" * len(OUTCOMES)]
    for family in [*FAMILIES, "all"]:
        rows = [r for r in results if family in ("all", r.case.family)]
        cells = [str(sum(counts[(f, o)] for f in FAMILIES if family in ("all", f)))
                 for o in OUTCOMES]
        lines.append(f"| {family} | {len(rows)} | " + " | ".join(cells) + " |")
    return lines


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", type=int, default=10_000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--timeout", type=float, default=60.0)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    per_round = len(cases(args.seed, 1))
    drawn = cases(args.seed, -(-args.cases // per_round))
    root = Path(args.out or tempfile.mkdtemp(prefix="minkplan-fuzz-"))
    t0 = time.monotonic()
    results = run_cases(drawn, root, timeout=args.timeout)
    lines = [f"# minkplan fuzz run: {len(results)} cases, seed {args.seed}, "
             f"{time.monotonic() - t0:.0f} s", "", *table(results), ""]
    for r in results:
        if r.outcome != "clean":
            lines.append(f"- {r.case.name} [{r.outcome}] minkplan {' '.join(r.case.argv)}: "
                         f"{r.detail}")
    sys.stdout.write("\n".join(lines) + f"\nfolders of the cases not clean: {root}\n")
    return 0 if all(r.outcome == "clean" for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
