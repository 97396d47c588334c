#!/usr/bin/env python3
"""Dump the matcher's results on fixed simulated frames, to compare two
versions of the code result for result.

    PYTHONPATH=/path/to/old python tools/dump_results.py old.json
    PYTHONPATH=$PWD        python tools/dump_results.py new.json
    python tools/dump_results.py --compare old.json new.json

Frames as tools/bench_paper.py draws them (``simulate.make_frame`` on
``maps/flat.lmap``, the paper's camera, 1 px / 1 deg noise, 3 clutter
lines): ``--poses`` per PEQ 1-5 for each seed of ``--seed`` with
:func:`matcher.localize`; the same with the frame's own roll and pitch
(``--roll-deg``, ``--pitch-error-deg``; the camera file's standard
deviations as bench_paper sets them); and ``--lost`` frames (PEQ 1 poses,
seed 7 as tools/bench_lost.py) with :func:`matcher.localize_global`; ``--hard``
frames (few segments seen, 14 clutter lines, 2.5 px / 2.5 deg noise) and as
many of clutter alone, for the failures' reasons. No time
budget, so every run does the same work. Each record is the result's
``to_dict()`` less the milliseconds of ``time_ms`` (its counts stay), with
the ranking, ``sets_found`` and stage 1's counters.

The matcher is imported from ``PYTHONPATH`` (this tool does not put its
checkout first), ``simulate`` from this tools folder.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

import matcher
from mapkit_harness.simulate import PEQ, PEQ_HELP, clutter_lines, make_frame, paper_camera

MAP = Path(__file__).resolve().parents[1] / "maps" / "flat.lmap"


def record(res) -> dict:
    """The comparable content of a result: its JSON less the milliseconds."""
    d = res.to_dict()
    d["time_ms"] = {k: v for k, v in d["time_ms"].items() if isinstance(v, int)}
    d["ranked"] = [[E if math.isfinite(E) else str(E), m, list(p)] for E, m, p in res.ranked]
    d["sets_found"] = int(res.sets_found)
    stage1 = dict(res.stage1)  # a dict, or the typed counters read as one
    d["stage1"] = {k: v for k, v in sorted(stage1.items()) if not k.startswith("ms_")}  # its counts, not its times
    return d


def dump(args) -> dict:
    linemap = matcher.load_map(MAP)
    tol = matcher.Tolerances(time_budget_ms=math.inf)
    level = paper_camera()
    tilted = replace(level, pitch_std_deg=0.75 * args.pitch_error_deg, roll_std_deg=0.67 * args.roll_deg)
    out: dict = {}
    for name, camera, roll, pitch_err in (("prior", level, 0.0, 0.0),
                                          ("attitude", tilted, args.roll_deg, args.pitch_error_deg)):
        poses = args.poses if name == "prior" else args.attitude_poses
        for seed in args.seed:
            for peq in args.peq:
                rng = np.random.default_rng([seed, peq])
                for i in range(poses):
                    fr = make_frame(linemap, camera, rng, peq, 1.0, 1.0, clutter=3, roll_deg=roll,
                                    pitch_error_deg=pitch_err)
                    res = matcher.localize(linemap, camera, fr.lines, fr.prior, fr.dt, fr.dyaw, tol)
                    out[f"{name}/seed{seed}/peq{peq}/{i}"] = record(res)
            print(f"{name} seed {seed} done", file=sys.stderr)
    # Hard frames, for the failures' reasons: few segments seen among much
    # clutter and noise, and frames of clutter alone.
    for seed in args.seed:
        for peq in (2, 5):
            rng = np.random.default_rng([seed, peq, 99])
            for i in range(args.hard):
                fr = make_frame(linemap, level, rng, peq, 2.5, 2.5, clutter=14, min_seen=3, max_seen=5)
                res = matcher.localize(linemap, level, fr.lines, fr.prior, fr.dt, fr.dyaw, tol)
                out[f"hard/seed{seed}/peq{peq}/{i}"] = record(res)
                res = matcher.localize(linemap, level, clutter_lines(rng, 12, level), fr.prior, fr.dt, fr.dyaw, tol)
                out[f"clutter/seed{seed}/peq{peq}/{i}"] = record(res)
    print("hard done", file=sys.stderr)
    rng = np.random.default_rng(7)
    for i in range(args.lost):
        fr = make_frame(linemap, level, rng, 1, 1.0, 1.0, clutter=3)
        out[f"lost/{i}"] = record(matcher.localize_global(linemap, level, fr.lines, tol))
    rng = np.random.default_rng(8)
    for i in range(args.lost_attitude):
        fr = make_frame(linemap, tilted, rng, 1, 1.0, 1.0, clutter=3, roll_deg=args.roll_deg,
                        pitch_error_deg=args.pitch_error_deg)
        out[f"lost_attitude/{i}"] = record(matcher.localize_global(linemap, tilted, fr.lines, tol))
    print("lost done", file=sys.stderr)
    return out


def compare(a_path: str, b_path: str) -> int:
    a, b = json.loads(Path(a_path).read_text()), json.loads(Path(b_path).read_text())
    for d in (*a.values(), *b.values()):
        d["stage1"] = {k: v for k, v in d["stage1"].items() if not k.startswith("ms_")}
    differ = [k for k in a if a[k] != b.get(k)] + [k for k in b if k not in a]
    for k in differ[:20]:
        print(f"{k}:\n  {a.get(k)}\n  {b.get(k)}")
    print(f"{len(a)} results, {len(differ)} differ")
    return 1 if differ else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Dump the matcher's results on fixed simulated frames.")
    ap.add_argument("out", nargs="?", help="JSON file to write")
    ap.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"), help="compare two dumps instead")
    ap.add_argument("--seed", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--peq", type=int, nargs="+", default=[1, 2, 3, 4, 5], choices=sorted(PEQ),
                    help="PEQ levels to run (default 1 to 5). " + PEQ_HELP)
    ap.add_argument("--poses", type=int, default=40, help="level frames per seed and PEQ")
    ap.add_argument("--attitude-poses", type=int, default=8, help="rolled and pitched frames per seed and PEQ")
    ap.add_argument("--roll-deg", type=float, default=3.0)
    ap.add_argument("--pitch-error-deg", type=float, default=2.0)
    ap.add_argument("--hard", type=int, default=25, help="hard and clutter-only frames per seed and PEQ (2, 5)")
    ap.add_argument("--lost", type=int, default=16, help="lost-mode frames of a level camera")
    ap.add_argument("--lost-attitude", type=int, default=4, help="lost-mode frames of a rolled, pitched camera")
    args = ap.parse_args(argv)
    if args.compare:
        return compare(*args.compare)
    if not args.out:
        ap.error("give the JSON file to write, or --compare OLD NEW")
    Path(args.out).write_text(json.dumps(dump(args), indent=0, sort_keys=True))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
