#!/usr/bin/env python3
"""A camera file that is wrong: what the matcher answers.

Simulated frames (:func:`mapkit_harness.simulate.make_frame`, the paper's
protocol) are made with the true camera and localised with a camera file
whose focal length is scaled (fx and fy alike), whose principal point is
shifted or whose height is off. Per map, wrong camera and seed set: the
frames accepted, those accepted more than 20 cm or 5 degrees off, and the
frames refused, with the check of the calibration
(:mod:`matcher.stage2.calibration_check`) off ("before") and on ("after");
"on 4 lines" counts the wrong answers after that match 4 lines only (too
few residuals to tell a calibration from the pose: the check does not
judge them); "refused for it" counts the refusals that name the calibration. The true
camera's row shows what the check costs right answers.

The seeds are split: the check's thresholds were chosen on the tuning
seeds; the held-out seeds (and the second map) were looked at after.

    python tools/bench_calibration.py                  # flat.lmap and the synthetic flat, PEQ 2
    python tools/bench_calibration.py --poses 3 --report docs/benchmarks/calibration.md
    python tools/bench_calibration.py --cameras 4 --poses 3   # a 4-camera ring rig, every camera file wrong alike

With ``--cameras N`` (N > 1) each frame is a ring rig's
(:func:`mapkit_harness.rigs.ring_rig`: N cameras of 70 degrees, 0.2 m
from the robot's centre; :func:`mapkit_harness.simulate.make_rig_frame`),
localised with every camera's file changed alike (a rig of one camera
model) by :func:`matcher.rig.localize_rig`, whose check runs the single
camera's on each camera (:mod:`matcher.rig.calibration`).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from tqdm import tqdm

import matcher
from linemap.rig import Rig
from mapkit_harness.rigs import ring_rig
from mapkit_harness.simulate import PEQ, PEQ_HELP, make_frame, make_rig_frame, paper_camera, pose_error
from mapkit_harness.tables import Table, add_report_option, reported
from matcher.rig import localize_rig
from matcher.tolerances import DEFAULT

ROOT = Path(__file__).resolve().parent.parent

#: The camera files tried: a name and the fields changed from the true camera's.
WRONG = {
    "true camera": lambda c: {},
    "fx, fy x 0.8": lambda c: dict(fx=c.fx * 0.8, fy=c.fy * 0.8),
    "fx, fy x 0.9": lambda c: dict(fx=c.fx * 0.9, fy=c.fy * 0.9),
    "fx, fy x 1.1": lambda c: dict(fx=c.fx * 1.1, fy=c.fy * 1.1),
    "fx, fy x 1.25": lambda c: dict(fx=c.fx * 1.25, fy=c.fy * 1.25),
    "fx, fy x 1.5": lambda c: dict(fx=c.fx * 1.5, fy=c.fy * 1.5),
    "fx, fy x 2": lambda c: dict(fx=c.fx * 2.0, fy=c.fy * 2.0),
    "cx + 40 px": lambda c: dict(cx=c.cx + 40.0),
    "cy + 40 px": lambda c: dict(cy=c.cy + 40.0),
    "height - 0.2 m": lambda c: dict(height_m=c.height_m - 0.2),
    "height - 0.1 m": lambda c: dict(height_m=c.height_m - 0.1),
    "height + 0.1 m": lambda c: dict(height_m=c.height_m + 0.1),
    "height + 0.2 m": lambda c: dict(height_m=c.height_m + 0.2),
}

#: An accepted answer farther than this from the truth is wrong (metres, degrees).
WRONG_M, WRONG_DEG = 0.2, 5.0


def load_maps(names: list[str]) -> dict:
    """The maps by name: ``flat`` (maps/flat.lmap, from the example DXF) and
    ``synthetic`` (the seven-room flat made in code)."""
    out = {}
    for name in names:
        if name == "flat":
            out[name] = matcher.load_map(ROOT / "maps" / "flat.lmap")
        else:
            from mapkit_harness.plans.buildings import cached_flat_map

            out[name] = cached_flat_map()
    return out


def outcome(linemap, camera, fr, tol) -> str:
    """``"right"``, ``"wrong"`` (accepted more than 20 cm / 5 deg off;
    ``"wrong on 4"`` when the answer matches 4 lines or fewer),
    ``"calibration"`` (refused, naming the calibration) or ``"refused"``.
    ``camera``: a camera model, or a :class:`~linemap.rig.Rig` for a rig's frame."""
    if isinstance(camera, Rig):
        res = localize_rig(linemap, camera, fr.lines, fr.prior, fr.dt, fr.dyaw, tol)
    else:
        res = matcher.localize(linemap, camera, fr.lines, fr.prior, fr.dt, fr.dyaw, tol)
    if not res:
        return "calibration" if "camera calibration" in res.reason else "refused"
    dm, ddeg = pose_error(res.pose, fr.pose)
    if dm <= WRONG_M and ddeg <= WRONG_DEG:
        return "right"
    return "wrong on 4" if len(res.matches) <= 4 else "wrong"


def wrong_camera(truth, name: str):
    """The camera file ``name`` of :data:`WRONG` made from ``truth`` (a
    camera, or a rig whose every camera's file is changed alike)."""
    if isinstance(truth, Rig):
        return Rig(tuple(replace(rc, camera=replace(rc.camera, **WRONG[name](rc.camera))) for rc in truth.cameras))
    return replace(truth, **WRONG[name](truth))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Frames localised with a wrong camera file: accepted, accepted and "
                                             "wrong, refused; without and with the check of the calibration.")
    ap.add_argument("--maps", nargs="+", default=["flat", "synthetic"], choices=["flat", "synthetic"])
    ap.add_argument("--peq", type=int, default=2, choices=sorted(PEQ),
                    help="the frames' PEQ level (default 2). " + PEQ_HELP)
    ap.add_argument("--cameras", type=int, default=1,
                    help="cameras of a ring rig per frame (default 1: the paper's single camera)")
    ap.add_argument("--poses", type=int, default=6, help="frames per seed (default 6)")
    ap.add_argument("--tuning", type=int, nargs="+", default=[0, 1, 2, 3], help="seeds the thresholds were tuned on")
    ap.add_argument("--held-out", type=int, nargs="+", default=[4, 5, 6, 7], help="seeds held out")
    ap.add_argument("--wrong", nargs="+", default=list(WRONG), choices=list(WRONG), metavar="CAMERA",
                    help="camera files to try (default: all of " + ", ".join(WRONG) + ")")
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)


def run(args) -> int:
    """The benchmark as ``main``'s arguments say; prints the table."""
    truth = paper_camera() if args.cameras == 1 else ring_rig(args.cameras, hfov_deg=70.0, radius_m=0.2)
    unchecked = replace(DEFAULT, verdict=replace(DEFAULT.verdict, calibration_judged=()))
    table = Table("map", "camera file", "seeds", "frames", "accepted before", "wrong before", "accepted after",
                  "wrong after", "on 4 lines", "refused for it")
    t0, calls = time.perf_counter(), 0
    # Minutes pass between the table's rows: a bar on stderr shows the run is
    # alive and how far it is (stdout keeps the table alone, for --report).
    seeds_all = args.tuning + args.held_out
    progress = tqdm(total=2 * len(set(args.maps)) * len(args.wrong) * len(seeds_all) * args.poses,
                    unit="localisation", file=sys.stderr, leave=False)
    for map_name, linemap in load_maps(args.maps).items():
        make = make_frame if args.cameras == 1 else make_rig_frame
        frames = {seed: [make(linemap, truth, rng, args.peq) for rng in [np.random.default_rng([seed, args.peq])]
                         for _ in range(args.poses)] for seed in seeds_all}
        for name in args.wrong:
            camera = wrong_camera(truth, name)
            for label, seeds in (("tuning", args.tuning), ("held out", args.held_out)):
                before = [outcome(linemap, camera, fr, unchecked) for s in seeds for fr in frames[s]]
                progress.update(len(before))
                after = [outcome(linemap, camera, fr, DEFAULT) for s in seeds for fr in frames[s]]
                progress.update(len(after))
                calls += 2 * len(before)
                wrong = ("wrong", "wrong on 4")
                table.row(map_name, name, f"{label} ({', '.join(map(str, seeds))})", len(before),
                          sum(o in ("right", *wrong) for o in before), sum(o in wrong for o in before),
                          sum(o in ("right", *wrong) for o in after), sum(o in wrong for o in after),
                          after.count("wrong on 4"), after.count("calibration"))
    progress.close()
    rig = "one camera" if args.cameras == 1 else f"a ring rig of {args.cameras} cameras"
    print(f"\n{calls} localisations in {time.perf_counter() - t0:.0f} s; {rig}; PEQ {args.peq}; wrong: accepted more than "
          f"{WRONG_M * 100:.0f} cm or {WRONG_DEG:g} deg from the truth")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
