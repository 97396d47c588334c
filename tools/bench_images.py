#!/usr/bin/env python3
"""The image path on rendered views: LSD (matcher.detect_lines), then
matcher.localize, per PEQ.

Each frame is a pose and prior drawn as in mapkit_harness/simulate.py; instead of
its simulated lines, the view is rendered (mapkit_harness/render.py: shaded walls,
floor, ceiling, door and window openings, anti-aliased, with grey-level
noise) and the lines are found by LSD. Per PEQ: the lines LSD found against
the model segments in view (median), how often the pose comes out right
(within 5 cm and 0.5 degree), the pose error (median), and the time of line
detection and of localisation (median over frames of the best of
``--repeat`` runs, milliseconds).

    python tools/bench_images.py                    # maps/flat.lmap, 20 frames per PEQ, seed 7
    python tools/bench_images.py --frames 5 --peq 1 5
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

import matcher

from mapkit_harness.render import render_view
from mapkit_harness.simulate import PEQ, PEQ_HELP, make_frame, paper_camera, pose_error
from mapkit_harness.tables import Table, add_report_option, reported

ROOT = Path(__file__).resolve().parent.parent

#: A pose within this much of the truth counts as right (metres, degrees).
RIGHT_M, RIGHT_DEG = 0.05, 0.5


def run_peq(linemap, camera, peq: int, frames: int, seed: int, supersample: int, repeat: int = 3) -> list[dict]:
    """Rows of one PEQ: per frame the segments in view, lines found, times
    (best of ``repeat`` runs, as tools/bench_paper.py times), pose error and
    whether it is right."""
    rng = np.random.default_rng([seed, peq])
    rows = []
    for _ in range(frames):
        frame = make_frame(linemap, camera, rng, peq, clutter=0)
        image = render_view(linemap, camera, frame.pose, supersample, rng=rng)
        detect_s, localize_s = [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            lines = matcher.detect_lines(image, camera)
            t1 = time.perf_counter()
            res = matcher.localize(linemap, camera, lines, frame.prior, frame.dt, frame.dyaw)
            detect_s.append(t1 - t0)
            localize_s.append(time.perf_counter() - t1)
        err = pose_error(res.pose, frame.pose) if res else (np.inf, np.inf)
        rows.append({"in_view": len(frame.lines), "found": len(lines), "detect_ms": min(detect_s) * 1e3,
                     "localize_ms": min(localize_s) * 1e3, "err_m": err[0], "err_deg": err[1],
                     "right": bool(res) and err[0] < RIGHT_M and err[1] < RIGHT_DEG})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Localise from rendered images (LSD, then matcher.localize).")
    ap.add_argument("--map", default=str(ROOT / "maps" / "flat.lmap"), help=".lmap map")
    ap.add_argument("--frames", type=int, default=20, help="frames per PEQ")
    ap.add_argument("--peq", type=int, nargs="+", default=sorted(PEQ), choices=sorted(PEQ),
                    help="PEQ levels to run (default 1 to 5). " + PEQ_HELP)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--supersample", type=int, default=2, help="rays per pixel along each axis when rendering")
    ap.add_argument("--repeat", type=int, default=3, help="timing: best of this many runs per frame")
    add_report_option(ap)
    args = ap.parse_args(argv)
    if min(args.frames, args.supersample, args.repeat) < 1:
        print("error: --frames, --supersample and --repeat must be at least 1", file=sys.stderr)
        return 2
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    try:
        linemap = matcher.load_map(args.map)
    except (OSError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    camera = paper_camera(1.2, 0.0)
    print(f"map {os.path.relpath(args.map)}; {args.frames} rendered frames per PEQ, seed {args.seed}; "
          f"right = within {RIGHT_M * 100:.0f} cm and {RIGHT_DEG} deg")
    table = Table("PEQ", "segments in view / lines found (med)", "right", "pose error med (cm / deg)",
                  "detect ms (med)", "localize ms (med)")
    for peq in args.peq:
        rows = run_peq(linemap, camera, peq, args.frames, args.seed, args.supersample, args.repeat)
        col = {k: np.array([r[k] for r in rows], dtype=float) for k in rows[0]}
        table.row(peq, f"{np.median(col['in_view']):.0f} / {np.median(col['found']):.0f}",
                  f"{100 * col['right'].mean():.0f}%",
                  f"{100 * np.median(col['err_m']):.1f} / {np.median(col['err_deg']):.2f}",
                  f"{np.median(col['detect_ms']):.1f}", f"{np.median(col['localize_ms']):.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
