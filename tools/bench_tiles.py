#!/usr/bin/env python3
"""Benchmark the region stage in one piece against tiles (mapkit.tiles) on
generated offices of n x n rooms of 5 m (``mapkit_harness.plans.office_grid``).

Each row is one ``mapkit build`` in a fresh process: wall and processor
seconds (the build's process and its worker processes), peak resident
memory of the build's own process and of its largest child (a tile's own
process, or a local Dask cluster's worker with ``--workers``), tiles, the
segments whose regions the tiles computed (a segment near a tile border is
computed by each tile it reaches), regions, file size. A row names
the build options it adds. Never ask for a one-piece build of 40 x 40 rooms
or more on a machine of 24 GB: it takes more than that (issue 46).

    python tools/bench_tiles.py                      # the default rows
    python tools/bench_tiles.py 10x10 20x20          # rows whose case contains one of these
    python tools/bench_tiles.py --rows "40:--workers 2" "60:"   # rows of your own: rooms:options
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shlex
import sys
import tempfile
import time
from pathlib import Path

from mapkit_harness.tables import Table, add_report_option, reported, row_from_child

#: (rooms per side, extra ``mapkit build`` options): one piece is forced by a
#: budget no floor reaches; tiles by the default budget (2000 MB) or a smaller one.
ROWS = [
    (10, "--memory-budget 1e6"),
    (10, "--memory-budget 400"),
    (20, "--memory-budget 1e6"),
    (20, ""),
    (20, "--workers 2"),
    (40, ""),
    (40, "--workers 2"),
]


def child(plan: Path, options: list[str]) -> dict:
    """One build of ``plan`` in this process (a fresh one): its figures."""
    import logging

    from mapkit.cli import main

    logging.disable(logging.WARNING)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.lmap"
        wall, t0 = time.perf_counter(), os.times()
        code = main(["build", str(plan), "-o", str(out), "-q", *options])
        t1 = os.times()
        wall = time.perf_counter() - wall
        if code != 0:
            raise SystemExit(code)
        from linemap.lmap import load_map

        m = load_map(out)
        stats = m.meta["stats"]["regions"]
        return {"wall_s": wall, "cpu_s": (t1.user + t1.system + t1.children_user + t1.children_system)
                - (t0.user + t0.system + t0.children_user + t0.children_system),
                "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                "worker_peak_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024,
                "free_m2": stats["free_space_area"], "tiles": stats.get("tiles", 1),
                "segments": stats["segments"], "computed": stats.get("tile_segments", stats["segments"]),
                "regions": len(m.list_offsets) - 1,
                "kib": out.stat().st_size / 1024, "mean_list": stats["mean_list_length"]}


def run_row(plan: Path, options: str) -> dict:
    cmd = [sys.executable, __file__, "--child", str(plan), "--", *shlex.split(options)]
    return row_from_child(cmd)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("only", nargs="*", help="run only rows whose case (e.g. 20x20) contains one of these")
    ap.add_argument("--rows", nargs="+", metavar="N:OPTIONS", help="rows of your own: rooms per side, options")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    add_report_option(ap)
    args, extra = ap.parse_known_args(argv)
    if args.child:
        opts = [e for e in [*args.only, *extra] if e != "--"]
        print(json.dumps(child(Path(args.child), opts)))
        return 0
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    rows = [(int(r.split(":", 1)[0]), r.split(":", 1)[1]) for r in args.rows] if args.rows else ROWS
    table = Table("office", "free m2", "options", "tiles", "wall s", "cpu s", "peak MB", "child peak MB",
                  "segments (computed)", "regions", "mean list", "KiB")
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        plans: dict[int, Path] = {}
        for n, options in rows:
            case = f"{n}x{n}"
            if args.only and not any(o in case for o in args.only):
                continue
            if n not in plans:
                from mapkit_harness.plans import office_grid

                plans[n] = Path(tmp) / f"office_{case}.dxf"
                office_grid(plans[n], n=n)
            try:
                r = run_row(plans[n], options)
            except Exception as exc:  # a benchmark reports every row, even a failing one
                table.row(case, "-", options or "(defaults)", f"failed: {exc}", *["-"] * 8)
                failed += 1
                continue
            table.row(case, f"{r['free_m2']:.0f}", options or "(defaults)", r["tiles"], f"{r['wall_s']:.0f}",
                      f"{r['cpu_s']:.0f}", f"{r['peak_mb']:.0f}",
                      f"{r['worker_peak_mb']:.0f}" if r["worker_peak_mb"] > 0 else "-",
                      f"{r['segments']} ({r['computed']})", r["regions"],
                      f"{r['mean_list']:.1f}", f"{r['kib']:.0f}")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
