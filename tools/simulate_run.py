#!/usr/bin/env python3
"""Simulate a robot run through a map: route, odometry, frames, truth.

The run itself (the route through the map's free space, the odometry with
its scale error and heading drift, the frames of visible map lines with
noise and clutter, ``--kidnap``) is :mod:`mapkit_harness.runs`, whose
docstring says how it is drawn; this writes it as files, the frames as
lines or as images rendered by :mod:`mapkit_harness.render`.

    python tools/simulate_run.py --map maps/flat.lmap --frames 150 -o run.jsonl --truth truth.txt
    python tools/simulate_run.py --frames 120 --kidnap 60 -o run.jsonl --truth truth.txt
    python tools/simulate_run.py --frames 40 --images frames/ -o run.jsonl   # rendered images
    python tools/simulate_run.py --rig rig.json --frames 60 -o run.jsonl --truth truth.txt

The JSON Lines file is what ``matcher track --frames`` reads; the truth is
a TUM trajectory (t x y z qx qy qz qw). The start pose is printed, for
``--prior``. With ``--rig RIG`` (a rig file, ``matcher.load_rig``) the run
is seen by the rig: each frame's ``"cameras"`` give every camera's lines
(or, with ``--images``, its image ``NNNNNN_K_NAME.png``), the poses are the
robot's (z 0 in the truth) and ``matcher track --rig RIG`` follows it.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import cv2
import numpy as np

import matcher
from matcher.tracking.trajectory import tum_text

from mapkit_harness.render import render_view
from mapkit_harness.runs import run_camera, simulate_run, write_run
from mapkit_harness.simulate import camera_pose

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Simulate a robot run through a map (frames with odometry).")
    ap.add_argument("--map", default=str(ROOT / "maps" / "flat.lmap"))
    ap.add_argument("--frames", type=int, default=120)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--step", type=float, default=0.15, help="metres driven a frame")
    ap.add_argument("--max-turn", type=float, default=15.0, help="degrees turned a frame")
    ap.add_argument("--noise-px", type=float, default=1.0)
    ap.add_argument("--clutter", type=int, default=2, help="clutter lines a frame")
    ap.add_argument("--dist-noise", type=float, default=0.03, help="odometry distance error (fraction)")
    ap.add_argument("--drift", type=float, default=1.5, help="odometry heading drift, degrees per metre")
    ap.add_argument("--kidnap", type=int, help="carry the robot away before this frame")
    ap.add_argument("--images", metavar="DIR", help="render images into DIR (tools/render.py) instead of lines")
    ap.add_argument("-o", "--out", required=True, help="JSON Lines file of the frames")
    ap.add_argument("--truth", help="TUM file of the true poses")
    ap.add_argument("--camera-out", help="write the camera.json used")
    ap.add_argument("--rig", help="a rig file: the run seen by the rig's cameras (one set of lines a camera)")
    args = ap.parse_args(argv)
    if args.rig and args.camera_out:
        ap.error("--camera-out writes the one camera of a run; a --rig run's cameras are the rig file's")
    linemap = matcher.load_map(args.map)
    camera = matcher.load_rig(args.rig) if args.rig else run_camera(linemap)
    run = simulate_run(linemap, camera, np.random.default_rng(args.seed), args.frames, args.step, args.max_turn,
                       args.noise_px, clutter=args.clutter, dist_noise=args.dist_noise,
                       drift_deg_per_m=args.drift, kidnap=args.kidnap)
    out = Path(args.out)
    images = None
    if args.images:
        images = _render(linemap, camera, run, Path(args.images), out, args.seed)
    write_run(run, out, images)
    if args.truth:
        z = 0.0 if args.rig else camera.height_m  # a rig's poses are the robot's, on the floor
        Path(args.truth).write_text(tum_text([(t, *p) for t, p in zip(run.times, run.truth)], z))
    if args.camera_out:
        Path(args.camera_out).write_text(json.dumps(camera.to_dict(), indent=1))
    x, y, yaw = run.truth[0]
    print(f"{len(run.times)} frames to {out}; start pose {x:.3f},{y:.3f},{yaw:.2f}"
          + (f"; kidnapped before frame {run.kidnap}" if run.kidnap else ""))
    return 0


def _render(linemap, camera, run, folder: Path, out: Path, seed: int) -> list:
    """Each frame's image rendered into ``folder`` (a rig's: one a camera,
    ``NNNNNN_K_NAME.png`` for camera K, each at its camera's pose); their paths relative
    to the JSON Lines file ``out``, a path a frame (a rig's: a list)."""
    folder.mkdir(parents=True, exist_ok=True)
    images = []
    for i, pose in enumerate(run.truth):
        views = ([(f"_{k}_{re.sub(r'[^A-Za-z0-9_.-]', '_', rc.name)}", rc.camera, camera_pose(rc.mount, pose))
                  for k, rc in enumerate(camera)]
                 if isinstance(camera, matcher.Rig) else [("", camera, pose)])
        paths = []
        for k, (suffix, cam, at) in enumerate(views):
            name = folder / f"{i:06d}{suffix}.png"
            rng = np.random.default_rng([seed, i] if not suffix else [seed, i, k])
            cv2.imwrite(str(name), render_view(linemap, cam, at, noise=2.0, rng=rng))
            paths.append(str(name.resolve().relative_to(out.resolve().parent, walk_up=True))
                         if sys.version_info >= (3, 12) else str(name.resolve()))
        images.append(paths if isinstance(camera, matcher.Rig) else paths[0])
    return images


if __name__ == "__main__":
    raise SystemExit(main())
