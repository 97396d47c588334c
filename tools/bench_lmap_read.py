#!/usr/bin/env python3
"""Reading maps: processor time and peak memory of ``linemap.lmap.decode``
on each map given, each read in a fresh child process (``ru_maxrss`` before
and after the decode: the file's bytes are read before). ``--reader FILE``
reads with another version of ``linemap/lmap.py`` (say one taken with
``git show COMMIT:linemap/lmap.py``), for a side-by-side comparison.

    python tools/bench_lmap_read.py maps/flat.lmap office40.lmap
    python tools/bench_lmap_read.py office40.lmap --reader /tmp/lmap_old.py
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

from mapkit_harness.tables import Table, add_report_option, reported

_CHILD = r"""
import importlib.util, json, resource, sys, time
path, reader = sys.argv[1], sys.argv[2]
if reader:
    spec = importlib.util.spec_from_file_location("lmap_reader", reader)
    lmap = importlib.util.module_from_spec(spec)
    sys.modules["lmap_reader"] = lmap
    spec.loader.exec_module(lmap)
else:
    from linemap import lmap
data = open(path, "rb").read()
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t = time.process_time()
m = lmap.decode(data, path)
cpu = time.process_time() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"regions": m.n_regions, "segments": m.n_segments, "entries": int(len(m.list_indices)),
                  "cpu": cpu, "before_mb": before / 1024, "peak_mb": peak / 1024}))
"""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Time and peak memory of reading .lmap maps, each in a fresh process.")
    ap.add_argument("maps", nargs="+", help=".lmap files")
    ap.add_argument("--reader", default="", help="a linemap/lmap.py to read with instead of the installed one")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args.maps, args.reader), __file__, argv)


def run(maps: list[str], reader: str) -> int:
    """One row per map; prints the table."""
    table = Table("map", "KiB", "regions", "segments", "list entries", "lists inflated MB", "cpu s",
                  "MB before", "peak MB")
    for path in maps:
        out = subprocess.run([sys.executable, "-c", _CHILD, path, reader], capture_output=True, text=True)
        if out.returncode:
            print(f"error: reading {path} failed: {out.stderr.strip().splitlines()[-1]}", file=sys.stderr)
            return 1
        r = json.loads(out.stdout)
        inflated = r["regions"] * ((r["segments"] + 7) // 8) / 1e6
        table.row(path, f"{Path(path).stat().st_size / 1024:.0f}", r["regions"], r["segments"], r["entries"],
                  f"{inflated:.0f}", f"{r['cpu']:.1f}", f"{r['before_mb']:.0f}", f"{r['peak_mb']:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
