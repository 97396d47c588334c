#!/usr/bin/env python3
"""Crafted maps against the loader: the error, the time and the peak memory
of each refusal (tracemalloc, which sees numpy's buffers), against the
file's size. The promise: a one-line LmapError, peak memory under 10 times
the file's size (tests/test_lmap_hostile.py asserts it, plus 16 MB for the
interpreter's own allocations).

    python tools/bench_lmap_hostile.py
"""

from __future__ import annotations

import argparse
import re
import sys
import time
import tracemalloc

from linemap.lmap import LmapError, decode

from mapkit_harness.crafted_maps import CASES, example_chunks
from mapkit_harness.tables import Table, add_report_option, reported


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Time and memory of refusing each crafted map (exit 1 if one is not).")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, run, __file__, argv)


def run() -> int:
    """Refuse each crafted map; prints the table."""
    chunks = example_chunks()
    table = Table("crafted map", "file KiB", "refused", "ms", "peak KiB", "peak / file")
    bad = 0
    for name, make, match in CASES:
        blob = make(chunks)
        tracemalloc.start()
        t = time.perf_counter()
        try:
            decode(blob, "crafted.lmap")
            refused = "NOT REFUSED"
        except LmapError as exc:
            refused = "yes" if re.search(match, str(exc)) and "\n" not in str(exc) else f"other: {exc}"
        ms = (time.perf_counter() - t) * 1e3
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        bad += refused != "yes"
        table.row(name, f"{len(blob) / 1024:.1f}", refused, f"{ms:.1f}", f"{peak / 1024:.0f}", f"{peak / len(blob):.2f}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
