#!/usr/bin/env python3
"""Print one synthetic frame of the paper's protocol on a map, or write it
(camera.json, lines.json, truth.json, frame.png) for ``matcher localize``.
With ``--rig RIG`` (a rig file or a Kalibr camchain that places cam0,
docs/inputs.md *Camera rigs*) one robot pose seen by every camera of the
rig: rig.json, one lines_NAME.json and frame_NAME.png a camera, truth.json.

The frames are :mod:`mapkit_harness.simulate`'s (docs/method.md section 9).

    python tools/simulate.py --peq 2 --seed 4
    python tools/simulate.py --peq 2 --seed 4 --out /tmp/frame
    python tools/simulate.py --peq 2 --seed 4 --rig rig.json --out /tmp/rig_frame
"""

from __future__ import annotations

import argparse
import json
import os
import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from linemap.errors import InputError
from linemap.rig import Rig
from mapkit_harness.simulate import PEQ, PEQ_HELP, make_frame, make_rig_frame, paper_camera


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        description="Synthetic frames for the paper's protocol (docs/method.md section 9): print or write one.")
    ap.add_argument("--map", default=str(Path(__file__).resolve().parents[1] / "maps" / "flat.lmap"),
                    help=".lmap map (default: maps/flat.lmap)")
    ap.add_argument("--peq", type=int, default=3, choices=sorted(PEQ),
                    help="the prior's PEQ level (default 3). " + PEQ_HELP)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--noise-px", type=float, default=1.0)
    ap.add_argument("--noise-deg", type=float, default=1.0)
    ap.add_argument("--clutter", type=int, default=3)
    ap.add_argument("--roll-deg", type=float, default=0.0,
                    help="the frame's camera rolled by up to this, degrees (drawn uniformly within +-)")
    ap.add_argument("--pitch-error-deg", type=float, default=0.0,
                    help="the frame's pitch off the camera file's by up to this, degrees (uniform within +-); "
                         "with either, camera.json says pitch_std_deg and roll_std_deg of those bounds")
    ap.add_argument("--out", metavar="DIR",
                    help="write camera.json, lines.json, truth.json and frame.png (the view rendered by "
                         "tools/render.py) there, for 'matcher localize'; with --rig rig.json, "
                         "lines_NAME.json and frame_NAME.png a camera, truth.json")
    ap.add_argument("--no-images", action="store_true",
                    help="with --out, write the lines and truth only (rendering the images is most of the time)")
    ap.add_argument("--rig", metavar="RIG",
                    help="a rig file or a Kalibr camchain placing cam0 (docs/inputs.md, Camera rigs): one robot "
                         "pose seen by each of its cameras")
    args = ap.parse_args(argv)
    import matcher

    try:
        m = matcher.load_map(args.map)
        if args.rig:
            return _rig_frame(args, m, matcher.load_rig(args.rig))
    except InputError as exc:
        print(f"error: {exc}")
        return 2
    cam = paper_camera()
    fr = make_frame(m, cam, np.random.default_rng(args.seed), args.peq, args.noise_px, args.noise_deg,
                    clutter=args.clutter, roll_deg=args.roll_deg, pitch_error_deg=args.pitch_error_deg)
    if args.roll_deg or args.pitch_error_deg:  # the camera file knows the bounds, not the frame's attitude
        cam = replace(cam, pitch_std_deg=0.75 * args.pitch_error_deg, roll_std_deg=0.67 * args.roll_deg)
        print(f"frame's pitch {fr.pitch_deg:.2f} deg, roll {fr.roll_deg:.2f} deg")
    x, y, yaw = fr.prior
    print(f"true pose {tuple(round(v, 3) for v in fr.pose)}; prior ({x:.2f}, {y:.2f}, {yaw:.1f}), "
          f"dt {fr.dt} m, dyaw {fr.dyaw} deg; {len(fr.lines)} lines")
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "camera.json").write_text(json.dumps(cam.to_dict()))
        (out / "lines.json").write_text(json.dumps({"lines": fr.lines.reshape(-1, 4).round(2).tolist()}))
        truth = {"pose": {"x": fr.pose[0], "y": fr.pose[1], "yaw_deg": fr.pose[2]},
                 "pitch_deg": fr.pitch_deg, "roll_deg": fr.roll_deg,
                 "prior": list(fr.prior), "dt": fr.dt, "dyaw": fr.dyaw, "matches": fr.true_matches()}
        (out / "truth.json").write_text(json.dumps(truth))
        written = "camera.json, lines.json, truth.json"
        if not args.no_images:  # the same view as an image (walls, floor and ceiling shaded), for --image
            import cv2
            from mapkit_harness.render import render_view

            real = replace(cam, pitch_deg=fr.pitch_deg, roll_deg=fr.roll_deg, pitch_std_deg=0.0, roll_std_deg=0.0)
            cv2.imwrite(str(out / "frame.png"), render_view(m, real, fr.pose, rng=np.random.default_rng(args.seed)))
            written += ", frame.png"
        print(f"wrote {out}/{written}; try:")
        common = (f"matcher localize --map {os.path.relpath(args.map)} --camera {out}/camera.json "
                  f"--prior {x:.3f},{y:.3f},{yaw:.2f} --dt {fr.dt:g} --dyaw {fr.dyaw:g}")
        print(f"  {common} --lines {out}/lines.json")
        if not args.no_images:
            print(f"  {common} --image {out}/frame.png")
    else:
        res = matcher.localize(m, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
        print(res.to_dict())
        print("true matches", fr.true_matches())
    return 0


def _rig_frame(args, m, rig) -> int:
    """One robot pose seen by every camera of ``rig``: printed, or written
    to ``--out`` as the single camera's frame is (one lines and one image
    file a camera)."""
    fr = make_rig_frame(m, rig, np.random.default_rng(args.seed), args.peq, args.noise_px, args.noise_deg,
                        clutter=args.clutter, roll_deg=args.roll_deg, pitch_error_deg=args.pitch_error_deg)
    # The rig as written: the lines and the images are the ideal pinhole's (the renderer knows no
    # distortion), so the cameras' distortion is dropped; the rig file knows the attitude's bounds,
    # not the frame's attitudes.
    std = dict(pitch_std_deg=0.75 * args.pitch_error_deg, roll_std_deg=0.67 * args.roll_deg) \
        if args.roll_deg or args.pitch_error_deg else {}
    if any(rc.camera.distortion for rc in rig):
        print("the cameras' distortion is left out: lines and images are the ideal pinhole's")
    rig = Rig(tuple(replace(rc, camera=replace(rc.camera, distortion=(), **std)) for rc in rig))
    x, y, yaw = fr.prior
    print(f"true pose {tuple(round(v, 3) for v in fr.pose)}; prior ({x:.2f}, {y:.2f}, {yaw:.1f}), "
          f"dt {fr.dt} m, dyaw {fr.dyaw} deg")
    safe = [re.sub(r"[^A-Za-z0-9_.-]", "_", rc.name) for rc in rig]  # a camera's name in its files' names
    files = {rc.name: s if safe.count(s) == 1 else f"{s}_{i}" for i, (rc, s) in enumerate(zip(rig, safe))}
    for rc, cf in zip(rig, fr.cameras):
        print(f"  {rc.name}: {len(cf.lines)} lines, {int((cf.truth >= 0).sum())} of map segments; pose "
              f"{tuple(round(v, 3) for v in cf.pose)}, pitch {cf.pitch_deg:.2f} deg, roll {cf.roll_deg:.2f} deg")
    if not args.out:
        return 0
    from linemap.rig_files import rig_to_dict

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "rig.json").write_text(json.dumps(rig_to_dict(rig)))
    cameras = []
    for rc, cf in zip(rig, fr.cameras):
        lines_file = f"lines_{files[rc.name]}.json"
        (out / lines_file).write_text(json.dumps({"lines": cf.lines.reshape(-1, 4).round(2).tolist()}))
        cameras.append({"name": rc.name, "lines": lines_file, "pose": list(cf.pose), "pitch_deg": cf.pitch_deg,
                        "roll_deg": cf.roll_deg, "matches": cf.true_matches()})
    truth = {"pose": {"x": fr.pose[0], "y": fr.pose[1], "yaw_deg": fr.pose[2]}, "prior": list(fr.prior),
             "dt": fr.dt, "dyaw": fr.dyaw, "cameras": cameras}
    (out / "truth.json").write_text(json.dumps(truth))
    if args.no_images:
        print(f"wrote {out}/rig.json, truth.json and, a camera each, lines_NAME.json ({', '.join(files.values())})")
        return 0
    # Each camera's view as an image (walls, floor and ceiling shaded), for images per camera.
    import cv2
    from mapkit_harness.render import render_view

    for i, (rc, cf) in enumerate(zip(rig, fr.cameras)):
        real = replace(rc.camera, pitch_deg=cf.pitch_deg, roll_deg=cf.roll_deg, pitch_std_deg=0.0,
                       roll_std_deg=0.0)
        image = render_view(m, real, cf.pose, rng=np.random.default_rng([args.seed, i]))
        cv2.imwrite(str(out / f"frame_{files[rc.name]}.png"), image)
    print(f"wrote {out}/rig.json, truth.json and, a camera each, lines_NAME.json and frame_NAME.png "
          f"({', '.join(files.values())})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
