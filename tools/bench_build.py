#!/usr/bin/env python3
"""Benchmark ``mapkit build`` on the bundled example, the real drawings and
meshes, and generated offices drawn as architects draw them.

Prints one row per input: its floor (free space, m2), seconds per pipeline
stage, segments, regions, mean visible-list length, file size, peak memory
(the ``ru_maxrss`` of a child process that does only that build) and
``load_map`` time (best of ``--load-repeats``). The generated cases
(``mapkit_harness/plans/drawings.py``) show time and memory against floor area:
offices of 4 x 4, 7 x 7 and 10 x 10 rooms of 5 m, and an open-plan office
of about 600 m2 with the traits of a real one (AIA layer names, facade
pieces and piers, door blocks, no closed outline). Targets (2-core machine):
flat.dxf < 5 s total, barcelona < 30 s, flat.lmap < 100 KB, load_map < 20 ms;
the open-plan office < 30 s and 1 GB, the 100-room office < 30 s and 500 MB.

    python tools/bench_build.py            # every case
    python tools/bench_build.py flat       # cases whose name contains 'flat'
    python tools/bench_build.py office     # the generated offices
    python tools/bench_build.py 10x10 --jobs 1   # the region stage in one thread
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from mapkit_harness.tables import Table, add_report_option, reported, row_from_child

ROOT = Path(__file__).resolve().parent.parent

#: name, input path, extra `mapkit build` options (as a user types them).
CASES = [
    ("flat.dxf", "maps/flat.dxf", []),
    ("barcelona-pavilion.dxf", "tests/data/barcelona-pavilion.dxf", ["--walls", "Walls", "--walls", "Columns", "--windows", "Crystal"]),
    ("thehouse.dxf", "tests/data/thehouse.dxf", ["--walls", "s001-*", "--units", "m"]),
    ("simple_room.glb", "tests/data/simple_room.glb", []),  # stored z-up despite glTF's convention
    ("hospital.stl", "tests/data/hospital.stl", []),
    # Generated (mapkit_harness/plans/drawings.py), written to a temporary folder first.
    ("office 4x4 rooms", "office_grid:4", []),
    ("office 7x7 rooms", "office_grid:7", []),
    ("office 10x10 rooms", "office_grid:10", []),
    ("open-plan office", "open_office", []),
]


def case_path(rel: str, tmp: Path) -> Path:
    """The input file of a case: a path under the project, or a generated plan written into ``tmp``."""
    if rel.startswith("office_grid:"):
        from mapkit_harness.plans import office_grid

        n = int(rel.split(":")[1])
        path = tmp / f"office_{n}x{n}.dxf"
        office_grid(path, n=n)
        return path
    if rel == "open_office":
        from mapkit_harness.plans import open_office

        path = tmp / "open_office.dxf"
        open_office(path)
        return path
    return ROOT / rel


def run_case(path: Path, extra: list[str], load_repeats: int) -> dict:
    from mapkit.cli import build_parser
    from mapkit.commands.build import options_from_args
    from linemap.lmap import load_map, save_map
    from mapkit.pipeline import build_map

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.lmap"
        args = build_parser().parse_args(["build", str(path), "-o", str(out), *extra])
        t0 = time.perf_counter()
        linemap, report = build_map(path, options_from_args(args))
        total = time.perf_counter() - t0
        t = time.perf_counter()
        size = save_map(out, linemap)
        write = time.perf_counter() - t
        loads = []
        for _ in range(load_repeats):
            t = time.perf_counter()
            load_map(out)
            loads.append(time.perf_counter() - t)
    import resource

    return {
        "floor_m2": float(linemap.meta.get("scene", {}).get("areas_m2", {}).get("free_space", float("nan"))),
        "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        **{f"t_{k}": v for k, v in report.seconds.items()},
        "t_write": write,
        "t_total": total + write,
        "segments": report.counts["segments"],
        "regions": report.counts["regions"],
        "mean_list": report.counts["mean_list_length"],
        "kib": size / 1024,
        "load_ms": 1000 * min(loads),
    }


def run_in_child(path: Path, extra: list[str], load_repeats: int) -> dict:
    """:func:`run_case` in a fresh interpreter, so that its peak memory is its own."""
    cmd = [sys.executable, __file__, "--child", str(path), "--load-repeats", str(load_repeats), "--", *extra]
    return row_from_child(cmd)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("only", nargs="*", help="run only cases whose name contains one of these")
    ap.add_argument("--load-repeats", type=int, default=20)
    ap.add_argument("--jobs", type=int, help="mapkit build --jobs (default: build's own)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    add_report_option(ap)
    args, extra = ap.parse_known_args(argv)
    if args.child:  # one build, its figures as JSON on the last line
        import logging

        logging.disable(logging.WARNING)
        # The build options follow "--": argparse hands them over as positionals.
        opts = [e for e in [*args.only, *extra] if e != "--"]
        print(json.dumps(run_case(Path(args.child), opts, args.load_repeats)))
        return 0
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    cols = [
        ("input", "s"), ("floor m2", ".0f"), ("import", ".2f"), ("edges", ".2f"), ("regions", ".2f"),
        ("assemble", ".2f"), ("write", ".2f"), ("total s", ".2f"), ("peak MB", ".0f"), ("segs", "d"),
        ("regions", "d"), ("mean list", ".1f"), ("KiB", ".1f"), ("load ms", ".2f"),
    ]
    table = Table(*(name for name, _ in cols))
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for name, rel, extra_opts in CASES:
            if args.only and not any(o in name for o in args.only):
                continue
            try:
                jobs = ["--jobs", str(args.jobs)] if args.jobs else []
                r = run_in_child(case_path(rel, Path(tmp)), [*extra_opts, *jobs], args.load_repeats)
            except Exception as exc:  # a benchmark reports every case, even a failing one
                table.row(name, f"failed: {exc}", *["-"] * (len(cols) - 2))
                failed += 1
                continue
            vals = [name, r["floor_m2"], r.get("t_import", 0), r.get("t_edges", 0), r.get("t_regions", 0),
                    r.get("t_assemble", 0), r["t_write"], r["t_total"], r["peak_mb"], r["segments"], r["regions"],
                    r["mean_list"], r["kib"], r["load_ms"]]
            table.row(*("-" if v != v else f"{v:{f}}" for v, (_, f) in zip(vals, cols)))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
