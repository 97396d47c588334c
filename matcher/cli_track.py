"""``matcher track``: follow a run (JSON Lines or a ROS bag) with :class:`matcher.Tracker`.

    matcher track --map MAP [--camera CAM] --frames RUN.jsonl|BAG
                  [--prior X,Y,YAW_DEG --dt M --dyaw DEG | --lost] [--storey NAME]
                  [--out TRAJ.txt] [--plot ROUTE.png] [--json]

On a building (MAP its ``building.json``) ``--storey`` names the prior's
storey; each frame names the storey the tracker is on.

One line per frame on stdout (one JSON object with ``--json``: the shape of
``localize --json`` plus ``t``, ``state`` and ``estimate``), a progress bar
on a terminal's stderr, then a summary. Exit 0 when at least one frame was
localised, 1 when none was, 2 for a usage error (before any output).
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

from linemap.errors import InputError
from matcher.cli import (EXIT_NOT_FOUND, EXIT_OK, UsageError, _camera, _input_file, _map_input, _prior_options,
                         _storey_scope, _tolerances)


def add_track_parser(sub) -> None:
    from matcher.cli import add_map_and_camera

    p = sub.add_parser("track", help="follow a moving robot through a run (frames with odometry)",
                       description="Follow a moving robot: each frame's prior is the last pose moved by the "
                                   "odometry; lost, it searches the map and confirms what it finds.")
    add_map_and_camera(p, camera_required=False)
    p.add_argument("--frames", required=True, metavar="RUN.jsonl|BAG",
                   help='JSON Lines, one frame a line: {"t": s, "odom": [x, y, yaw_deg], "lines": [[u1, v1, u2, '
                        'v2], ...]} or "image": "path"; or a ROS 1 .bag, ROS 2 bag folder, .mcap or .db3 file')
    p.add_argument("--prior", help="pose at the first frame X,Y,YAW_DEG (metres, degrees)")
    p.add_argument("--dt", type=float, help="position bound of the prior, metres")
    p.add_argument("--dyaw", type=float, help="heading bound of the prior, degrees")
    p.add_argument("--lost", action="store_true", help="no prior: search the map first, then follow")
    p.add_argument("--image-topic", help="bag topic of the images (sensor_msgs/Image or CompressedImage; "
                   "default: the only one)")
    p.add_argument("--camera-info-topic", help="bag topic of the intrinsics (sensor_msgs/CameraInfo; default: "
                   "the only one, when no camera is given)")
    p.add_argument("--odom-topic", help="bag topic of the odometry (nav_msgs/Odometry; default: the only one)")
    p.add_argument("--odom-distance-fraction", type=float, metavar="F",
                   help="odometry position error per metre driven (default 0.05)")
    p.add_argument("--odom-deg-per-m", type=float, metavar="DEG", help="odometry heading drift per metre (default 2)")
    p.add_argument("--odom-deg-per-deg", type=float, metavar="F",
                   help="odometry heading error per degree turned (default 0.05)")
    p.add_argument("--budget-ms", type=float, metavar="MS",
                   help="time budget of each frame's search from its prior (default: no limit)")
    p.add_argument("--relocalise-budget-ms", type=float, metavar="MS",
                   help="time budget of a search of the whole map when lost (default 1000)")
    p.add_argument("--out", metavar="TRAJ.txt", help="write the trajectory (TUM format: t x y z qx qy qz qw)")
    p.add_argument("--plot", metavar="ROUTE.png", help="draw the route, the odometry and the accepted poses")
    p.add_argument("--json", action="store_true", help="one JSON object per frame")


def _settings(args):
    from matcher.tolerances import TRACKING

    changes = {name: getattr(args, name) for name in
               ("odom_distance_fraction", "odom_deg_per_m", "odom_deg_per_deg", "relocalise_budget_ms")
               if getattr(args, name) is not None}
    try:
        return replace(TRACKING, **changes)
    except InputError as exc:
        raise UsageError(str(exc).replace("tracking setting ", "--").replace("_", "-")) from None


class _Source:
    """The frames of --frames and the camera they are seen with."""

    def __init__(self, args) -> None:
        from linemap.camera import Camera
        from matcher.tracking.rosbag import BagFrames, is_bag

        path = args.frames
        self.bag = None
        if is_bag(path):
            if not Path(path).exists():
                raise UsageError(f"frames {path} not found; check the path")
            self.bag = BagFrames(path, args.image_topic, args.camera_info_topic, args.odom_topic)
            if args.camera or args.camera_k:
                self.camera = _camera(args, Camera)
            else:
                self.camera = self.bag.camera(args.height_m, args.pitch_deg, args.roll_deg)
            self.total = len(self.bag)
        else:
            for opt in ("image_topic", "camera_info_topic", "odom_topic"):
                if getattr(args, opt):
                    raise UsageError(f"--{opt.replace('_', '-')} is for bags; {path} is read as JSON Lines")
            _input_file(path, "frames file")
            if not (args.camera or args.camera_k):
                raise UsageError("give the camera: --camera CAM.json (or --camera-k with --image-size)")
            self.camera = _camera(args, Camera)
            from matcher.tracking.frames import count_frames

            self.total = count_frames(path)
        self.path = path

    def frames(self):
        from matcher.lines import detect_lines

        if self.bag is not None:
            return self.bag.frames(lambda img: detect_lines(img, self.camera))
        from matcher.cli import _read_image
        from matcher.tracking.frames import read_jsonl

        return read_jsonl(self.path, lambda image_path: _read_image(str(image_path), self.camera))

    def close(self) -> None:
        if self.bag is not None:
            self.bag.close()


def run_track(args) -> int:
    import matcher
    from linemap.atomic import check_output_path, write_atomic
    from matcher.tracking.trajectory import tum_text

    prior = _prior_options(args)
    tol = _tolerances(args)
    settings = _settings(args)
    _map_input(args.map)
    inputs = [args.map, args.frames] + ([args.camera] if args.camera else [])
    for out in (args.out, args.plot):
        if out:
            check_output_path(out, inputs)
    if args.plot and Path(args.plot).suffix.lower() not in (".png", ".jpg", ".jpeg"):
        raise UsageError(f"--plot {args.plot}: give a .png or .jpg file")
    linemap = matcher.load_map(args.map)
    _storey_scope(linemap, args.storey, lost=False)
    if args.storey is not None and prior is None:
        raise UsageError("--storey names the storey of --prior; with --lost the tracker searches every storey")
    source = _Source(args)
    try:
        tracker = matcher.Tracker(linemap, source.camera, *(prior or (None, None, None)),
                                  tolerances=tol, settings=settings, storey=args.storey)
        frames, odoms = _follow(tracker, source, args)
    finally:
        source.close()
    if args.out:  # on a building, z above the storey's floor
        floor = {s.name: s.elevation_m for s in linemap.storeys} if isinstance(linemap, matcher.Building) else {}
        poses = [(f["t"], f["estimate"]["x"], f["estimate"]["y"], f["estimate"]["yaw_deg"],
                  floor.get(f.get("storey"), 0.0)) for f in frames if f.get("estimate") and not f["skipped"]]
        write_atomic(args.out, tum_text(poses, source.camera.height_m))
    if args.plot:
        _write_plot(args.plot, linemap, frames, odoms)
    ok = sum(1 for f in frames if f["ok"])
    if not args.json:
        states = {s: sum(1 for f in frames if f["state"] == s) for s in ("tracking", "coasting", "relocalising")}
        print(f"{ok} of {len(frames)} frames localised; " + ", ".join(f"{s} {n}" for s, n in states.items()))
    return EXIT_OK if ok else EXIT_NOT_FOUND


def _follow(tracker, source: _Source, args) -> tuple[list[dict], list]:
    """Every frame through the tracker, printed as it comes; the frames as
    dicts and the odometry of each (None for a skipped frame)."""
    progress = sys.stderr.isatty() and (args.json or not sys.stdout.isatty())
    frames, odoms, ok = [], [], 0
    for i, fr in enumerate(source.frames(), 1):
        if fr.error:
            out = tracker.step(fr.t, None, None)  # keeps the state, says the frame was skipped
            out.reason = f"frame skipped ({fr.where}): {fr.error}"
        else:
            out = tracker.step(fr.t, fr.odom, fr.lines)
            if out.reason.startswith("frame skipped"):
                out.reason = out.reason.replace("frame skipped", f"frame skipped ({fr.where})", 1)
        d = out.to_dict()
        frames.append(d)
        odoms.append(None if fr.error else fr.odom)
        ok += bool(out)
        print(json.dumps(d) if args.json else _human(d), flush=True)
        if progress:
            print(f"\rframe {i}/{source.total}  {out.state:<12} {ok} localised", end="", file=sys.stderr, flush=True)
    if progress:
        print(file=sys.stderr)
    return frames, odoms


def _human(d: dict) -> str:
    head = f"t={d['t']:.3f} {d['state']:<12}" + (f" storey {d['storey']!r}" if d.get("storey") else "")
    e = d.get("estimate")
    where = "" if not e else (f" x={e['x']:.3f} y={e['y']:.3f} yaw={e['yaw_deg']:.1f}"
                              f" (bounds {e['dt']:.2f} m, {e['dyaw_deg']:.1f} deg)")
    return f"{head}{where}  {'ok' if d['ok'] else d['reason']}"


def _write_plot(path: str, linemap, frames: list[dict], odoms: list) -> None:
    """The route picture; on a building, of the storey of the last frame
    that names one (the first mapped storey if none does), with the frames on it."""
    import cv2

    from linemap.atomic import write_atomic
    from linemap.building import Building
    from matcher.tracking.route_plot import draw_route

    if isinstance(linemap, Building):
        named = [f["storey"] for f in frames if f.get("storey")]
        storey = linemap.storey(named[-1]) if named else linemap.mapped[0]
        on = [k for k, f in enumerate(frames) if f.get("storey") in (None, storey.name)]
        linemap, frames, odoms = storey.map, [frames[k] for k in on], [odoms[k] for k in on]
    img = draw_route(linemap, frames, odoms)
    ok, data = cv2.imencode(Path(path).suffix.lower(), img)
    if not ok:
        raise UsageError(f"--plot {path}: the picture could not be encoded")
    write_atomic(path, data.tobytes())
