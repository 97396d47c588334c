#!/usr/bin/env python3
"""Render a grey image of a map seen from a pose (:mod:`mapkit_harness.render`:
walls, floor, ceiling and openings shaded, anti-aliased, with seeded noise).

    python tools/render.py --pose 2.0,1.5,30 -o view.png
    python tools/render.py --pose 2.0,1.5,30 --pano 2048 --camera-height 1.4 -o pano.png

``--pano WIDTH`` renders an equirectangular panorama (WIDTH x WIDTH/2,
:mod:`matcher.panorama`'s convention: centre column along the pose's
heading plus ``--pano-yaw-offset``, columns clockwise, up at the top) taken
``--camera-height`` metres above the floor (default: the camera file's).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import cv2
import numpy as np

from linemap.argv import join_negative_values
from mapkit_harness.render import render_panorama, render_view


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Grey images of a map seen from a pose, for testing the image path end to end.")
    ap.add_argument("--map", default=str(Path(__file__).resolve().parents[1] / "maps" / "flat.lmap"),
                    help=".lmap map (default: maps/flat.lmap)")
    ap.add_argument("--camera", help="camera.json (default: the paper's camera of the simulator)")
    ap.add_argument("--pose", required=True, help="X,Y,YAW_DEG of the camera")
    ap.add_argument("-o", "--out", required=True, help="output image (PNG)")
    ap.add_argument("--supersample", type=int, default=3)
    ap.add_argument("--noise", type=float, default=2.0, help="grey-level noise sigma")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--pano", type=int, metavar="WIDTH",
                    help="render an equirectangular panorama WIDTH x WIDTH/2 pixels instead of a pinhole view")
    ap.add_argument("--camera-height", type=float, help="the panorama's height above the floor, metres "
                    "(default: the camera's)")
    ap.add_argument("--pano-yaw-offset", type=float, default=0.0,
                    help="heading of the panorama's centre column relative to the pose's, degrees, counter-clockwise")
    args = ap.parse_args(join_negative_values(sys.argv[1:] if argv is None else list(argv), ("--pose",)))
    import matcher

    from mapkit_harness.simulate import paper_camera

    try:
        pose = tuple(float(v) for v in args.pose.split(","))
        if len(pose) != 3 or not all(map(math.isfinite, pose)):
            raise ValueError
    except ValueError:
        print(f"error: --pose must be X,Y,YAW_DEG (three finite numbers), got {args.pose!r}", file=sys.stderr)
        return 2
    try:
        m = matcher.load_map(args.map)
        cam = matcher.Camera.load(args.camera) if args.camera else paper_camera()
    except (OSError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    rng = np.random.default_rng(args.seed)
    if args.pano is not None:
        height = cam.height_m if args.camera_height is None else args.camera_height
        if args.pano < 64 or args.pano % 2 or args.pano > 16384:
            print(f"error: --pano must be an even width from 64 to 16384 pixels, got {args.pano}", file=sys.stderr)
            return 2
        if not (math.isfinite(height) and height > 0 and math.isfinite(args.pano_yaw_offset)):
            print("error: --camera-height must be above 0 m and --pano-yaw-offset finite", file=sys.stderr)
            return 2
        img = render_panorama(m, pose, height, args.pano, args.pano_yaw_offset, args.supersample, args.noise, rng)
    else:
        img = render_view(m, cam, pose, args.supersample, noise=args.noise, rng=rng)
    if not cv2.imwrite(args.out, img):
        print(f"error: could not write {args.out} (use a .png or .jpg name in an existing folder)", file=sys.stderr)
        return 2
    print(f"wrote {args.out} ({img.shape[1]}x{img.shape[0]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
