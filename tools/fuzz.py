"""Fuzz campaign: damaged and hostile inputs for every entry point, each
case under a time and memory bound.

    python tools/fuzz.py                                  # small campaign
    python tools/fuzz.py --dxf 2000 --mesh 500 --zind 500 --segments 500 --lmap 500 --matcher 2000 --save /tmp/fuzz-failures

The families, the bounded run of a case, the classifier and the campaign are
``mapkit_harness.fuzz`` (its docstring lists the families). Each case must
end in a clean one-line error, a falsy result with its reason, or a valid
result; anything else (a bug, a run past ``--bound-s`` seconds or the
``--mem-gb`` address-space limit) is a failure. ``--save DIR`` writes each
failing case as a folder (its input files and ``case.json`` with the
commands), and ``--replay DIR`` runs such a folder again.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

from mapkit_harness.fuzz.campaign import campaign
from mapkit_harness.fuzz.cases import load_case
from mapkit_harness.fuzz.classify import ACCEPTED, BUG, OUTCOMES, OVER
from mapkit_harness.fuzz.run import run_bounded
from mapkit_harness.tables import markdown_table


def print_table(table: dict, seconds: float) -> None:
    """Counts per family and outcome, and the wall clock."""
    print(markdown_table(("family", "cases", "clean errors", "valid results", "falsy results", "bugs",
                          "over time bound"),
                         [(fam, sum(row.values()), *(row[c] for c in OUTCOMES)) for fam, row in table.items()]))
    print(f"({seconds:.0f} s wall clock)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dxf", type=int, default=40, help="DXF cases (default 40)")
    ap.add_argument("--mesh", type=int, default=20, help="mesh cases (default 20)")
    ap.add_argument("--zind", type=int, default=40, help="ZInD annotation cases (default 40)")
    ap.add_argument("--segments", type=int, default=40, help="segments-file cases (default 40)")
    ap.add_argument("--lmap", type=int, default=100, help=".lmap cases (default 100)")
    ap.add_argument("--matcher", type=int, default=100, help="matcher-input cases (default 100)")
    ap.add_argument("--building", type=int, default=40, help="building manifest cases (default 40)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2, help="cases run at once (default 2)")
    ap.add_argument("--bound-s", type=float, default=60.0, help="time bound of one case, seconds (default 60)")
    ap.add_argument("--mem-gb", type=float, default=3.0, help="address-space limit of one case, GiB (default 3)")
    ap.add_argument("--save", type=Path, metavar="DIR", help="write each failing case into DIR")
    ap.add_argument("--minutes", type=float, default=math.inf,
                    help="start no case after this many minutes (the table counts the cases run)")
    ap.add_argument("--replay", type=Path, metavar="CASE_DIR", help="run one saved case and print its outcome")
    args = ap.parse_args(argv)
    if args.replay and not (args.replay / "case.json").is_file():
        ap.error(f"--replay {args.replay}: no case.json there; give a folder --save wrote (or tests/data/fuzz/NAME)")
    with tempfile.TemporaryDirectory(prefix="fuzz-") as scratch:
        if args.replay:
            out = run_bounded(load_case(args.replay), Path(scratch) / "case", args.bound_s, args.mem_gb)
            print(f"{out.kind} in {out.seconds:.1f} s: {out.detail}")
            return 0 if out.kind in ACCEPTED else 1
        t0 = time.monotonic()
        counts = {"dxf": args.dxf, "mesh": args.mesh, "zind": args.zind, "segments": args.segments, "lmap": args.lmap,
                  "matcher": args.matcher, "building": args.building}
        table = campaign(counts, args.seed, args.workers, args.bound_s, args.mem_gb, args.save, Path(scratch),
                         minutes=args.minutes)
    print(f"seed {args.seed}, {args.workers} workers, bound {args.bound_s:g} s and {args.mem_gb:g} GiB a case")
    print_table(table, time.monotonic() - t0)
    bad = sum(row[BUG] + row[OVER] for row in table.values())
    return 1 if bad else 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    raise SystemExit(main())
