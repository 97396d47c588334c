#!/usr/bin/env python3
"""What a time budget (``Tolerances.time_budget_ms``, ``matcher localize
--budget-ms``) does to latency and answers.

The frames of tools/bench_paper.py (seed 0, 100 per PEQ, noise 1 px and 1
degree, 3 clutter lines) are localised once per budget, the budgets taking
turns frame by frame so that the machine's drift falls on all alike. Per
PEQ and budget: the correct match ranked first and the answers accepted
(%), wrong answers accepted (frames whose accepted matches are not all
true, as tools/bench_paper.py judges them), frames whose search the budget
cut, and the latency's median, p95 and maximum (one run per frame,
milliseconds).

    python tools/bench_budget.py                       # PEQ 3 to 5; no budget, 200, 100, 50 ms
    python tools/bench_budget.py --peq 5 --budgets 0 30 --poses 50
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import matcher

from mapkit_harness.scoring import indistinguishable, is_correct
from mapkit_harness.simulate import PEQ, PEQ_HELP, make_frame, paper_camera
from mapkit_harness.tables import Table, add_report_option, reported

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Latency and answers of matcher.localize under time budgets.")
    ap.add_argument("--map", default=str(ROOT / "maps" / "flat.lmap"), help=".lmap map")
    ap.add_argument("--peq", type=int, nargs="+", default=[3, 4, 5], choices=sorted(PEQ),
                    help="PEQ levels to run (default 3 4 5). " + PEQ_HELP)
    ap.add_argument("--poses", type=int, default=100, help="frames per PEQ (seed 0, as tools/bench_paper.py)")
    ap.add_argument("--budgets", type=float, nargs="+", default=[0, 200, 100, 50],
                    help="budgets in milliseconds; 0 for none")
    add_report_option(ap)
    args = ap.parse_args(argv)
    if args.poses < 1 or min(args.budgets) < 0:
        print("error: --poses must be at least 1 and --budgets at least 0", file=sys.stderr)
        return 2
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    linemap = matcher.load_map(args.map)
    camera = paper_camera(1.2, 0.0)
    budgets = [b if b > 0 else math.inf for b in args.budgets]
    tols = [replace(matcher.Tolerances(), time_budget_ms=b) for b in budgets]
    matcher.localize(linemap, camera, [[0, 0, 10, 10]] * 3, (0, 0, 0), 0.1, 1)  # warm-up (imports, caches)
    print(f"map {args.map}; {args.poses} frames per PEQ, seed 0; one run per frame and budget")
    table = Table("PEQ", "budget ms", "correct first", "accepted", "wrong accepted", "cut by the budget",
                  "ms med / p95 / max")
    for peq in args.peq:
        rng = np.random.default_rng([0, peq])
        frames = [make_frame(linemap, camera, rng, peq, 1.0, 1.0, clutter=3) for _ in range(args.poses)]
        for fr in frames[:3]:  # the map's caches for this part of it
            matcher.localize(linemap, camera, fr.lines, fr.prior, fr.dt, fr.dyaw)
        runs = [[] for _ in tols]  # per budget: (result, ms) per frame
        for i, fr in enumerate(frames):
            for b in (range(len(tols)) if i % 2 else reversed(range(len(tols)))):  # alternate who goes first
                t0 = time.perf_counter()
                res = matcher.localize(linemap, camera, fr.lines, fr.prior, fr.dt, fr.dyaw, tols[b])
                runs[b].append((res, (time.perf_counter() - t0) * 1e3))
        same = [indistinguishable(linemap, camera, fr) for fr in frames]
        for budget, rows in zip(budgets, runs):
            first = accepted = wrong = cut = 0
            for fr, equiv, (res, _) in zip(frames, same, rows):
                truth = {tuple(m) for m in fr.true_matches()}
                first += bool(res.ranked) and is_correct(res.ranked[0][1], truth, equivalent=equiv)
                cut += bool(res.stage1.out_of_time)
                accepted += bool(res)
                wrong += bool(res) and not is_correct(res.matches, truth, equivalent=equiv)
            ms = np.array([t for _, t in rows])
            n = len(frames)
            table.row(peq, "none" if math.isinf(budget) else f"{budget:g}", f"{100 * first / n:.0f}%",
                      f"{100 * accepted / n:.0f}%", wrong, cut,
                      f"{np.median(ms):.1f} / {np.percentile(ms, 95):.1f} / {ms.max():.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
