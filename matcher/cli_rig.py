"""``matcher localize`` for a rig of cameras (``--rig RIG`` with one
``--lines`` or ``--image`` file per camera) and for a 360-degree panorama
(``--pano PANO --camera-height H``): the frame's lines per camera, then
:func:`matcher.localize_rig` or :func:`matcher.localize_rig_global`.
"""

from __future__ import annotations

import argparse
import math

from linemap.errors import InputError


class RigUsageError(InputError):
    """A rig or panorama option given wrongly; the message says how."""


def add_rig_options(p: argparse.ArgumentParser) -> None:
    """The rig and panorama options of ``matcher localize``."""
    p.add_argument("--rig", help="rig file (JSON: cameras with their poses on the robot) or a Kalibr camchain.yaml; "
                   "give one --lines or --image file per camera, in the rig's order (docs/inputs.md)")
    p.add_argument("--cam0-pose", metavar="X,Y,YAW_DEG,HEIGHT_M[,PITCH_DEG,ROLL_DEG]",
                   help="where a Kalibr camchain's cam0 is on the robot (metres forward and left, heading, "
                        "height; degrees), unless the file says")
    p.add_argument("--pano", metavar="PANO", help="an equirectangular 360-degree image (twice as wide as high; its "
                   "centre column looks along the robot's heading, columns run clockwise seen from above, the top "
                   "row looks straight up); needs --camera-height")
    p.add_argument("--camera-height", dest="height_m", type=float, metavar="H",
                   help="the panorama camera's height above the floor, metres (same as --height-m)")
    p.add_argument("--pano-yaw-offset", type=float, default=0.0, metavar="DEG",
                   help="heading of the panorama's centre column relative to the robot's, degrees "
                        "counter-clockwise (default 0)")


def rig_requested(args) -> bool:
    """Do the options ask for a rig or a panorama?"""
    return bool(getattr(args, "rig", None) or getattr(args, "pano", None))


def check_sources(args) -> None:
    """UsageError unless the camera and line sources go together: one
    camera (--camera or --camera-k), a rig or a panorama; one lines or
    image file for one camera, one per camera of a rig, none with a
    panorama."""
    given = [o for o, v in (("--camera", args.camera), ("--camera-k", args.camera_k), ("--rig", args.rig),
                            ("--pano", args.pano)) if v]
    if len(given) != 1:
        raise RigUsageError("give one of --camera, --camera-k, --rig or --pano" if not given else
                            f"{' and '.join(given)} do not go together; give one of them")
    files = args.lines or args.image or []
    if args.pano:
        if files:
            raise RigUsageError("--pano is the frame's image; drop --lines/--image")
        if args.height_m is None:
            raise RigUsageError("--pano needs --camera-height (the panorama camera's height above the floor, metres)")
    elif not files:
        raise RigUsageError("give --lines LINES.json or --image IMAGE (one per camera with --rig)")
    elif not args.rig and len(files) != 1:
        raise RigUsageError(f"{len(files)} lines/image files for one camera; give one (or a --rig of "
                            f"{len(files)} cameras)")
    if args.cam0_pose and not args.rig:
        raise RigUsageError("--cam0-pose places a Kalibr rig's first camera; it goes with --rig")


def rig_frame(args, read_lines, read_image):
    """``(rig, lines per camera)`` of the options: a rig file with one lines
    or image file per camera, or a panorama cut into its views."""
    if args.pano:
        return _panorama_frame(args)
    rig = rig_of(args)
    files = args.lines or args.image
    if len(files) != len(rig):
        raise RigUsageError(f"the rig has {len(rig)} cameras ({', '.join(rig.names)}) and {len(files)} "
                            f"{'--lines' if args.lines else '--image'} files were given; give one per camera, "
                            "in the rig's order")
    if args.lines:
        return rig, [read_lines(f) for f in files]
    return rig, [read_image(f, rc.camera) for f, rc in zip(files, rig)]


def _panorama_frame(args):
    """The panorama's rig of views and each view's lines."""
    import cv2

    from matcher.panorama import panorama_lines, panorama_rig

    image = cv2.imread(args.pano, cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise RigUsageError(f"panorama {args.pano} could not be read (PNG, JPEG, ... expected)")
    rig = panorama_rig(image.shape[1], args.height_m, args.pano_yaw_offset)
    return rig, panorama_lines(image, rig)


def rig_of(args):
    """The rig of ``--rig``, its Kalibr cam0 placed by ``--cam0-pose``."""
    import matcher

    return matcher.load_rig(args.rig, _cam0(args.cam0_pose))


def _cam0(text: str | None):
    """The --cam0-pose option as a placement dict, or None."""
    if not text:
        return None
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) not in (4, 6) or not all(math.isfinite(x) for x in v):
        raise RigUsageError(f"--cam0-pose takes X,Y,YAW_DEG,HEIGHT_M[,PITCH_DEG,ROLL_DEG], got {text!r}")
    names = ("x", "y", "yaw_deg", "height_m", "pitch_deg", "roll_deg")
    return dict(zip(names, v))


def one_floor(linemap, storey: str | None):
    """The map a rig is localised on: ``linemap`` itself, or a building's
    storey named by ``--storey`` (or its only one); a rig over every storey
    of a building is not searched yet."""
    from linemap.building import Building

    if not isinstance(linemap, Building):
        if storey is not None:
            raise RigUsageError(f"--storey {storey!r} is for a building (building.json); this map is one floor: "
                                "drop --storey")
        return linemap
    if storey is None and len(linemap.mapped) != 1:
        raise RigUsageError("a rig on a building is localised on one storey: give --storey NAME "
                            f"({', '.join(s.name for s in linemap.mapped)})")
    return (linemap.storey(storey) if storey is not None else linemap.mapped[0]).map


def localize_frame(args, linemap, rig, lines, prior, tol):
    """The rig's frame localised: from the prior, or lost."""
    import matcher

    if prior is None:
        return matcher.localize_rig_global(linemap, rig, lines, tolerances=tol)
    return matcher.localize_rig(linemap, rig, lines, *prior, tolerances=tol)
