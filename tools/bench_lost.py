#!/usr/bin/env python3
"""Time lost mode (matcher.localize_global) on simulated frames.

Each frame is drawn as in mapkit_harness/simulate.py (PEQ 1 poses; the prior is not
used), then localised with no prior: one search per region of the map. The
table gives per frame the seconds, the regions tried, the pose error and
whether the answer is right (within 10 cm and 1 degree), then the median.

    python tools/bench_lost.py                  # maps/flat.lmap, 8 frames, seed 7
    python tools/bench_lost.py --frames 20 --first-accepted
    python tools/bench_lost.py --budget-ms 3000    # each call bounded: the largest regions first
    python tools/bench_lost.py --focal-scale 1.97  # frames seen at fx x 1.97, the matcher given the file's fx:
                                                   # every accepted answer is wrong and counted so
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import matcher

from mapkit_harness.simulate import make_frame, paper_camera, pose_error
from mapkit_harness.tables import Table, add_report_option, reported

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Time lost mode (localize_global) on simulated frames.")
    ap.add_argument("--map", default=str(ROOT / "maps" / "flat.lmap"), help=".lmap map")
    ap.add_argument("--frames", type=int, default=8, help="frames to localise")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--first-accepted", action="store_true", help="stop at the first accepted region (the paper's loop)")
    ap.add_argument("--budget-ms", type=float, default=math.inf,
                    help="time budget of each call, milliseconds (Tolerances.time_budget_ms; default none)")
    ap.add_argument("--focal-scale", type=float, default=1.0,
                    help="the frames' camera has the file's focal length times this (a wrong camera file; "
                         "default 1: right)")
    ap.add_argument("--search", choices=("tree", "structure"), default=None,
                    help="the search that ranks places (Tolerances.search; default the matcher's for a single "
                         "camera, the tree)")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    tol = replace(matcher.Tolerances(), time_budget_ms=args.budget_ms, search=args.search)
    linemap = matcher.load_map(args.map)
    camera = paper_camera(1.2, 0.0)
    seen_by = replace(camera, fx=camera.fx * args.focal_scale, fy=camera.fy * args.focal_scale)
    rng = np.random.default_rng([args.seed, 1])
    budget = "" if math.isinf(args.budget_ms) else f"; budget {args.budget_ms:g} ms per call"
    focal = "" if args.focal_scale == 1.0 else f"; frames seen at {args.focal_scale:g} x the camera file's focal length"
    print(f"map {args.map}: {linemap.n_segments} segments, {linemap.n_regions} regions; "
          f"{'first accepted region' if args.first_accepted else 'every region'}{budget}{focal}; "
          f"search {args.search or 'default'}")
    table = Table("frame", "s", "regions tried", "position err m", "yaw err deg", "right")
    seconds, right, wrong = [], 0, 0
    for i in range(args.frames):
        frame = make_frame(linemap, seen_by, rng, 1, 1.0, 1.0, clutter=3)
        t0 = time.perf_counter()
        res = matcher.localize_global(linemap, camera, frame.lines, tol, first_accepted=args.first_accepted)
        seconds.append(time.perf_counter() - t0)
        err = pose_error(res.pose, frame.pose) if res else (float("nan"), float("nan"))
        ok = bool(res) and err[0] < 0.1 and err[1] < 1.0
        right += ok
        wrong += bool(res) and not ok
        table.row(i, f"{seconds[-1]:.1f}", res.time_ms.get("regions_tried"), f"{err[0]:.3f}", f"{err[1]:.2f}",
                  "yes" if ok else "no: " + (res.reason or "wrong pose"))
    print(f"median {np.median(seconds):.1f} s (min {min(seconds):.1f}, max {max(seconds):.1f}); right {right} of "
          f"{args.frames}, accepted and wrong {wrong}, not localised {args.frames - right - wrong}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
