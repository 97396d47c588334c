#!/usr/bin/env python3
"""Time ``matcher.detect_lines`` on real photographs.

Each photo is timed as it is and resized to 640x480 and 1280x1024 (the
sizes the targets name: 30 ms and 100 ms median on this 2-core machine),
median and p95 of ``--repeat`` runs; also LSD alone, the raw segments it
finds and the lines that come out. Photos: the committed
``tests/data/rocket.jpg`` (public domain) and any given on the command line.

    python tools/bench_lines.py
    python tools/bench_lines.py ~/photos/*.jpg --repeat 20
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

import matcher

from mapkit_harness.tables import Table, add_report_option, reported

ROOT = Path(__file__).resolve().parent.parent


def _times(fn, repeat: int) -> tuple[float, float, object]:
    out, t = None, []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        t.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(t)), float(np.percentile(t, 95)), out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("photos", nargs="*", help="more photos (any format OpenCV reads)")
    ap.add_argument("--repeat", type=int, default=10, help="runs per case (median and p95 of them)")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    paths = [ROOT / "tests" / "data" / "rocket.jpg"] + [Path(p) for p in args.photos]
    table = Table("photo", "size", "LSD segments", "lines out", "LSD ms (median)", "detect_lines ms (median / p95)")
    lsd = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD)
    for path in paths:
        img = cv2.imread(str(path))
        if img is None:
            print(f"bench_lines: error: cannot read {path}", file=sys.stderr)
            return 2
        for size in (None, (640, 480), (1280, 1024)):
            im = img if size is None else cv2.resize(img, size, interpolation=cv2.INTER_AREA)
            grey = cv2.cvtColor(im, cv2.COLOR_BGR2GRAY)
            lsd_med, _, raw = _times(lambda: lsd.detect(grey)[0], args.repeat)
            med, p95, lines = _times(lambda: matcher.detect_lines(im), args.repeat)
            n_raw = 0 if raw is None else len(raw)
            label = "as it is" if size is None else "resized"
            table.row(f"{path.name} ({label})", f"{im.shape[1]}x{im.shape[0]}", n_raw, len(lines), f"{lsd_med:.1f}",
                      f"{med:.1f} / {p95:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
