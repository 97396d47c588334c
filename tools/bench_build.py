#!/usr/bin/env python3
"""Benchmark ``mapkit build`` on the bundled example and the real drawings and meshes.

Prints one row per input: seconds per pipeline stage, segments, regions,
mean visible-list length, file size and ``load_map`` time (best of
``--load-repeats``). Targets (2-core machine): flat.dxf < 5 s total,
barcelona < 30 s, flat.lmap < 100 KB, load_map < 20 ms.

    python tools/bench_build.py            # every case
    python tools/bench_build.py flat       # cases whose name contains 'flat'
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: name, input path, extra `mapkit build` options (as a user types them).
CASES = [
    ("flat.dxf", "maps/flat.dxf", []),
    ("barcelona-pavilion.dxf", "tests/data/barcelona-pavilion.dxf", ["--walls", "Walls", "--walls", "Columns", "--windows", "Crystal"]),
    ("thehouse.dxf", "tests/data/thehouse.dxf", ["--walls", "s001-*", "--units", "m"]),
    ("simple_room.glb", "tests/data/simple_room.glb", []),  # stored z-up despite glTF's convention
    ("hospital.stl", "tests/data/hospital.stl", []),
]


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
    return {
        **{f"t_{k}": v for k, v in report.seconds.items()},
        "t_write": write,
        "t_total": total + write,
        "segments": report.counts["segments"],
        "regions": report.counts["regions"],
        "mean_list": report.counts["mean_list_length"],
        "kib": size / 1024,
        "load_ms": 1000 * min(loads),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("only", nargs="*", help="run only cases whose name contains one of these")
    ap.add_argument("--load-repeats", type=int, default=20)
    args = ap.parse_args(argv)
    cols = [
        ("input", 24, "s"), ("import", 7, ".2f"), ("edges", 6, ".2f"), ("regions", 7, ".2f"),
        ("assemble", 8, ".2f"), ("write", 6, ".2f"), ("total s", 7, ".2f"), ("segs", 5, "d"),
        ("regions", 7, "d"), ("mean list", 9, ".1f"), ("KiB", 7, ".1f"), ("load ms", 7, ".2f"),
    ]
    print(" | ".join(f"{name:>{w}}" if i else f"{name:<{w}}" for i, (name, w, _) in enumerate(cols)))
    print("-|-".join("-" * w for _, w, _ in cols))
    failed = 0
    for name, rel, extra in CASES:
        if args.only and not any(o in name for o in args.only):
            continue
        try:
            r = run_case(ROOT / rel, extra, args.load_repeats)
        except Exception as exc:  # a benchmark reports every case, even a failing one
            print(f"{name:<24} | failed: {exc}")
            failed += 1
            continue
        vals = [name, r.get("t_import", 0), r.get("t_edges", 0), r.get("t_regions", 0), r.get("t_assemble", 0),
                r["t_write"], r["t_total"], r["segments"], r["regions"], r["mean_list"], r["kib"], r["load_ms"]]
        print(" | ".join(f"{v:<{w}{f}}" if i == 0 else f"{v:>{w}{f}}" for i, (v, (_, w, f)) in enumerate(zip(vals, cols))))
        sys.stdout.flush()
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
