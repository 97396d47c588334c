"""``matcher track``: follow a run (JSON Lines or a ROS bag) with :class:`matcher.Tracker`.

    matcher track --map MAP [--camera CAM] --frames RUN.jsonl|BAG
                  [--prior X,Y,YAW_DEG --dt M --dyaw DEG | --lost] [--storey NAME]
                  [--out TRAJ.txt] [--plot ROUTE.png] [--json]
    matcher track --map MAP --rig RIG [--topics T0,T1,...] --frames RUN.jsonl|BAG (...)

On a building (MAP its ``building.json``) ``--storey`` names the prior's
storey; each frame names the storey the tracker is on. A rig (``--rig``)
gives frames of one camera's lines or image per camera (JSON Lines
``"cameras"``, or one image topic a camera in a bag); it is tracked on one
storey of a building (``--storey``, with or without a prior).

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
                        'v2], ...]} or "image": "path" (with --rig: "cameras": [{"lines": ...} or {"image": ...}, '
                        '...], one a camera); or a ROS 1 .bag, ROS 2 bag folder, .mcap or .db3 file')
    p.add_argument("--rig", help="rig file (JSON: cameras with their poses on the robot) or a Kalibr camchain.yaml, "
                   "instead of a camera: each frame gives every camera's lines or image, in the rig's order")
    p.add_argument("--cam0-pose", metavar="X,Y,YAW_DEG,HEIGHT_M[,PITCH_DEG,ROLL_DEG]",
                   help="where a Kalibr camchain's cam0 is on the robot, unless the file says")
    p.add_argument("--topics", metavar="T0,T1,...", help="with --rig and a bag: each camera's image topic, in the "
                   "rig's order (default: the rig file's \"topic\" of each camera)")
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
    """The frames of --frames and the camera (or rig, ``rig`` then set) they are seen with."""

    def __init__(self, args) -> None:
        from matcher.tracking.rosbag import is_bag

        self.path, self.bag = args.frames, None
        self.rig = _rig(args)
        if is_bag(self.path):
            self._open_bag(args)
        else:
            for opt in ("image_topic", "camera_info_topic", "odom_topic", "topics"):
                if getattr(args, opt):
                    raise UsageError(f"--{opt.replace('_', '-')} is for bags; {self.path} is read as JSON Lines")
            _input_file(self.path, "frames file")
            if self.rig is None and not (args.camera or args.camera_k):
                raise UsageError("give the camera: --camera CAM.json (or --camera-k with --image-size), "
                                 "or a --rig RIG")
            from matcher.tracking.frames import check_run_file, count_frames

            check_run_file(self.path)
            self.total = count_frames(self.path)
        if self.rig is not None:
            self.camera = self.rig
        elif self.bag is None or args.camera or args.camera_k:
            from linemap.camera import Camera

            self.camera = _camera(args, Camera)
        else:
            self.camera = self.bag.camera(args.height_m, args.pitch_deg, args.roll_deg)

    def _open_bag(self, args) -> None:
        from matcher.tracking.rosbag import BagFrames

        if not Path(self.path).exists():
            raise UsageError(f"frames {self.path} not found; check the path")
        if self.rig is None:
            if args.topics:
                raise UsageError("--topics names a rig's image topics; give --rig (or --image-topic for one camera)")
            self.bag = BagFrames(self.path, args.image_topic, args.camera_info_topic, args.odom_topic)
        else:
            for opt in ("image_topic", "camera_info_topic"):
                if getattr(args, opt):
                    raise UsageError(f"--{opt.replace('_', '-')} is for one camera; a rig's bag has one image topic "
                                     "per camera (--topics T0,T1,... or each camera's \"topic\" in the rig file)")
            self.bag = BagFrames(self.path, odom_topic=args.odom_topic, image_topics=_rig_topics(args, self.rig))
        self.total = len(self.bag)

    def frames(self):
        from matcher.lines import detect_lines

        rig = self.rig
        if self.bag is not None:
            if rig is not None:
                return self.bag.rig_frames(lambda img, k: detect_lines(img, rig[k].camera))
            return self.bag.frames(lambda img: detect_lines(img, self.camera))
        from matcher.cli import _read_image
        from matcher.tracking.frames import read_jsonl

        if rig is not None:
            return read_jsonl(self.path, lambda image_path, k: _read_image(str(image_path), rig[k].camera), rig)
        return read_jsonl(self.path, lambda image_path: _read_image(str(image_path), self.camera))

    def close(self) -> None:
        if self.bag is not None:
            self.bag.close()


def _rig(args):
    """The rig of --rig (None without it); UsageError with a camera's options."""
    if not args.rig:
        if args.cam0_pose:
            raise UsageError("--cam0-pose places a Kalibr rig's first camera; it goes with --rig")
        return None
    given = [f"--{o.replace('_', '-')}" for o in ("camera", "camera_k", "image_size", "height_m", "pitch_deg",
                                                  "roll_deg") if getattr(args, o) is not None]
    if given:
        raise UsageError(f"{', '.join(given)} describe one camera; a rig file gives each of its cameras: drop "
                         f"{'them' if len(given) > 1 else 'it'} or --rig")
    from matcher.cli_rig import rig_of

    _input_file(args.rig, "rig file")
    return rig_of(args)


def _rig_topics(args, rig) -> list[str]:
    """Each rig camera's image topic: --topics, else the rig file's ('' where it names none)."""
    if not args.topics:
        return [rc.topic for rc in rig]
    topics = [t.strip() for t in args.topics.split(",")]
    if len(topics) != len(rig) or not all(topics):
        raise UsageError(f"--topics takes one image topic per camera of the rig, in its order ({len(rig)}: "
                         f"{', '.join(rig.names)}), got {args.topics!r}")
    return topics


def run_track(args) -> int:
    import matcher
    from linemap.atomic import check_output_path, write_atomic
    from matcher.tracking.trajectory import tum_text

    prior = _prior_options(args)
    tol = _tolerances(args)
    settings = _settings(args)
    _map_input(args.map)
    inputs = [args.map, args.frames] + [f for f in (args.camera, args.rig) if f]
    for out in (args.out, args.plot):
        if out:
            check_output_path(out, inputs)
    if args.plot and Path(args.plot).suffix.lower() not in (".png", ".jpg", ".jpeg"):
        raise UsageError(f"--plot {args.plot}: give a .png or .jpg file")
    linemap = matcher.load_map(args.map)
    _storey_scope(linemap, args.storey, lost=False)
    if args.rig:  # a rig is tracked on one storey of a building
        from matcher.cli_rig import one_floor

        one_floor(linemap, args.storey)
    elif args.storey is not None and prior is None:
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
        # z: the camera's height, or 0 for a rig (its poses are the robot's, on the floor)
        write_atomic(args.out, tum_text(poses, 0.0 if source.rig is not None else source.camera.height_m))
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
    # a skipped frame says so in the state's column (the tracker's state is unchanged by it)
    head = f"t={d['t']:.3f} {'skipped' if d.get('skipped') else d['state']:<12}" + (f" storey {d['storey']!r}" if d.get("storey") else "")
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
