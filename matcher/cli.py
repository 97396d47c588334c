"""The ``matcher`` command line (also ``python -m matcher``).

    matcher localize --map MAP --camera CAM.json (--lines LINES.json | --image IMG)
                     (--prior X,Y,YAW_DEG --dt METRES --dyaw DEG | --lost)
                     [--storey NAME] [--budget-ms MS] [--json]
    matcher localize --map MAP --rig RIG.json (--lines L0.json L1.json ... | --image I0 I1 ...) (...)
    matcher localize --map MAP --pano PANO.jpg --camera-height H [--pano-yaw-offset DEG] (...)
    matcher track --map MAP [--camera CAM] --frames RUN.jsonl|BAG
                  [--prior X,Y,YAW_DEG --dt M --dyaw DEG | --lost] [--storey NAME]
                  [--out TRAJ.txt] [--plot ROUTE.png] [--json]
    matcher track --map MAP --rig RIG [--topics T0,T1,...] --frames RUN.jsonl|BAG (...)

MAP is a ``.lmap`` map or a building (its ``building.json``, or the folder
holding it): ``--storey`` names the prior's storey; ``--lost`` searches
every storey (only ``--storey``'s, when given) and prints the storey.

Human-readable output by default, one JSON object on stdout with ``--json``
(the result shape of docs/architecture.md). Errors a user can cause (an
:class:`~linemap.errors.InputError` or an ``OSError``) print one line
``matcher: error: ...`` on stderr and exit 2, never a traceback. A failed
localisation is not an error: it prints its reason and exits 1. Any other
exception is a bug: one line ``matcher: internal error: ...`` asking for a
report, exit 3, and its traceback with ``--debug``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
from dataclasses import replace
from pathlib import Path

from linemap.argv import join_negative_values
from linemap.building import StoreyNeeded
from linemap.errors import OUT_OF_MEMORY, InputError, add_debug_option, report_bug

#: Exit codes: localised, not localised (a valid answer), user error; a bug
#: exits with linemap.errors.EXIT_BUG (3).
EXIT_OK, EXIT_NOT_FOUND, EXIT_USAGE = 0, 1, 2


class UsageError(InputError):
    """A mistake the user can fix; the message says how."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # noqa: D401 - argparse API
        self.exit(EXIT_USAGE, f"matcher: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    from linemap import __version__

    parser = _Parser(prog="matcher", description="Localise a camera in a line map (.lmap): one image (localize) or a run (track).")
    parser.add_argument("--version", action="version", version=f"matcher {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    p = sub.add_parser("localize", help="pose from image lines and a prior",
                       description="Pose of the camera from image lines (or an image) and a pose prior.")
    add_map_and_camera(p, camera_required=False)
    src = p.add_mutually_exclusive_group()
    src.add_argument("--lines", nargs="+", help='lines.json {"lines": [[u1, v1, u2, v2], ...]} (undistorted '
                     "pixels); one per camera with --rig")
    src.add_argument("--image", nargs="+", help="image file; lines are detected with LSD; one per camera with --rig")
    from matcher.cli_rig import add_rig_options

    add_rig_options(p)
    p.add_argument("--prior", help="pose prior X,Y,YAW_DEG (metres, degrees)")
    p.add_argument("--dt", type=float, help="position bound of the prior, metres")
    p.add_argument("--dyaw", type=float, help="heading bound of the prior, degrees")
    p.add_argument("--lost", action="store_true",
                   help="no prior, any heading (lost mode): the places the lines vote for, then every region; "
                        "a median 0.1 to 0.5 s a frame, seconds when the votes do not settle it (bound it with --budget-ms)")
    p.add_argument("--budget-ms", type=float, metavar="MS",
                   help="time budget: stop searching after MS milliseconds and verify what was found "
                        "(default 30000: Tolerances.time_budget_ms)")
    p.add_argument("--max-lines", type=int, metavar="N",
                   help="most image lines taken (default 2000: Tolerances.max_lines); more is an error")
    p.add_argument("--search", choices=("tree", "structure"),
                   help="how places are ranked before stage 2 verifies them: 'tree', the paper's interpretation "
                        "tree, or 'structure', every pose of the prior scored from the scene's structure "
                        "(docs/matcher.md; default per kind of frame, matcher.search.DEFAULTS)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    from matcher.cli_track import add_track_parser

    add_track_parser(sub)
    add_debug_option(parser, sub.choices.values())
    return parser


def add_map_and_camera(p: argparse.ArgumentParser, camera_required: bool) -> None:
    """The --map and camera options (shared by localize and track)."""
    p.add_argument("--map", required=True, help=".lmap map built by 'mapkit build', or a building's manifest "
                   "(building.json, or its folder: 'mapkit build model.ifc -o DIR')")
    p.add_argument("--storey", metavar="NAME", help="on a building: the storey of the prior (with --lost: search "
                   "only it; default: every storey)")
    cam = p.add_mutually_exclusive_group(required=camera_required)
    cam.add_argument("--camera", help="camera.json (width, height, fx, fy, cx, cy, height_m, pitch_deg), an OpenCV "
                     "calibration file (YAML, XML, JSON) or a ROS camera_info YAML")
    cam.add_argument("--camera-k", metavar="FX,FY,CX,CY", help="pinhole intrinsics in pixels, with --image-size")
    p.add_argument("--image-size", metavar="WxH", help="image width and height in pixels (with --camera-k)")
    p.add_argument("--height-m", type=float, help="camera height above the floor, metres (needed with a "
                   "calibration file or --camera-k; overrides a camera.json's)")
    p.add_argument("--roll-deg", type=float, help="camera roll, degrees, the right side down positive (default 0 "
                   "with a calibration file or --camera-k; overrides a camera.json's)")
    p.add_argument("--pitch-deg", type=float, help="camera pitch, degrees, down positive (default 0 with a "
                   "calibration file or --camera-k; overrides a camera.json's)")


def _parse_prior(text: str) -> tuple[float, float, float]:
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise UsageError(f"--prior must be X,Y,YAW_DEG (three numbers), got {text!r}")
    return vals[0], vals[1], vals[2]


def _map_input(path: str) -> None:
    """UsageError unless --map names a readable file, or a folder holding a building's manifest."""
    from linemap.building import MANIFEST_NAME

    if not (Path(path).is_dir() and (Path(path) / MANIFEST_NAME).is_file()):
        _input_file(path, "map file", "build one with 'mapkit build'")


def _storey_scope(linemap, storey: str | None, lost: bool):
    """What ``--storey`` leaves to search: the map, the building, or (lost
    mode on one storey) that storey of the building; UsageError for
    ``--storey`` with a map of one floor."""
    from linemap.building import Building

    if not isinstance(linemap, Building):
        if storey is not None:
            raise UsageError(f"--storey {storey!r} is for a building (building.json); this map is one floor: "
                             "drop --storey")
        return linemap
    return linemap.storey(storey) if lost and storey is not None else linemap


def _input_file(path: str, what: str, hint: str = "check the path") -> Path:
    """``path`` as a Path if it is a readable file; else UsageError."""
    p = Path(path)
    if p.is_dir():
        raise UsageError(f"{what} {path} is a directory; give the file")
    if not p.is_file():
        raise UsageError(f"{what} {path} not found; {hint}")
    if not os.access(p, os.R_OK):
        raise UsageError(f"{what} {path} is not readable (permission denied)")
    return p


def _read_lines(path: str):
    p = _input_file(path, "lines file")
    try:
        data = json.loads(p.read_bytes())
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError) as exc:
        why = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
        raise UsageError(f"lines file {path} is not valid JSON ({why})") from None
    except OSError as exc:
        raise UsageError(f"lines file {path} could not be read ({exc.strerror or exc})") from None
    if not isinstance(data, dict) or "lines" not in data or not isinstance(data["lines"], list):
        raise UsageError(f'lines file {path} must hold {{"lines": [[u1, v1, u2, v2], ...]}}')
    if any(isinstance(v, bool) for row in data["lines"] if isinstance(row, list) for v in row):
        raise UsageError(f"lines file {path} holds true/false where pixel coordinates belong")
    return data["lines"]


def _read_image(path: str, camera):
    import cv2

    from matcher.lines import detect_lines

    _input_file(path, "image file")
    with _c_stderr_silenced():
        img = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
    if img is None:
        raise UsageError(f"image file {path} could not be read (PNG, JPEG, ... expected)")
    return detect_lines(img, camera)


@contextlib.contextmanager
def _c_stderr_silenced():
    """File descriptor 2 pointed at /dev/null for the block: OpenCV's image
    codecs print their own complaints there ("libpng error: Read Error"),
    which the one-line error that follows says better."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _prior_options(args):
    """``(prior, dt, dyaw)`` from the options, or None for ``--lost``;
    UsageError unless exactly one of the two forms is given."""
    given = [name for name in ("prior", "dt", "dyaw") if getattr(args, name) is not None]
    if args.lost:
        if given:
            raise UsageError(f"--lost takes no prior; drop --{', --'.join(given)} or drop --lost")
        return None
    if len(given) < 3:
        missing = [f"--{n}" for n in ("prior", "dt", "dyaw") if n not in given]
        raise UsageError(f"missing {', '.join(missing)}: give --prior X,Y,YAW_DEG with --dt and --dyaw, "
                         "or --lost when the robot has no estimate")
    return _parse_prior(args.prior), args.dt, args.dyaw


def _tolerances(args):
    """The matcher's tolerances with the options' budget; UsageError if it
    is not a positive number."""
    from matcher.tolerances import DEFAULT

    tol = DEFAULT
    if getattr(args, "max_lines", None) is not None:
        if args.max_lines < 1:
            raise UsageError(f"--max-lines must be a positive number of lines, got {args.max_lines}")
        tol = replace(tol, max_lines=args.max_lines)
    if args.budget_ms is None:
        return tol
    if not (math.isfinite(args.budget_ms) and args.budget_ms > 0):
        raise UsageError(f"--budget-ms must be a positive number of milliseconds, got {args.budget_ms:g}")
    return replace(tol, time_budget_ms=args.budget_ms)


def _region_progress(done: int, total: int) -> None:
    """Lost mode's progress on a terminal's stderr (one line, rewritten)."""
    end = "\n" if done == total else ""
    print(f"\rlost mode: region {done}/{total}", end=end, file=sys.stderr, flush=True)


def _human(res, n_lines: int) -> str:
    t = ", ".join(f"{k} {v:.1f}" for k, v in res.time_ms.items() if k not in ("regions_tried", "places_tried"))
    if "regions_tried" in res.time_ms:
        t += f" ({res.time_ms.get('places_tried', 0)} voted places, {res.time_ms['regions_tried']} regions tried)"
    if res and res.stage1.get("out_of_time"):
        t += " (search stopped at the time budget)"
    if not res:
        text = f"not localised: {res.reason}\n  {res.hypotheses} hypotheses from {n_lines} lines; time ms: {t}"
        if any("storey" in c for c in res.candidates):  # a building's candidates: where each is
            text += "".join(f"\n  candidate: storey {c['storey']!r} x={c['x']:.3f} m  y={c['y']:.3f} m  "
                            f"yaw={c['yaw_deg']:.2f} deg" for c in res.candidates)
        return text
    x, y, yaw = res.pose
    ru = "none" if res.runner_up_score is None else f"{res.runner_up_score:.3g}"
    std = "" if res.pose_std is None else "  (std {:.3f} m, {:.3f} m, {:.2f} deg)".format(*res.pose_std)
    on = "" if res.storey is None else f"storey {res.storey!r}  "
    return (
        f"{on}pose x={x:.3f} m  y={y:.3f} m  yaw={yaw:.2f} deg{std}\n"
        f"  score E={res.score:.3g} (runner-up {ru}), {res.hypotheses} hypotheses, "
        f"{len(res.matches)} of {n_lines} lines matched\n"
        f"  matches [segment, line]: {res.matches}\n"
        + "".join(f"  camera {c['name']}: {len(c['matches'])} matches"
                  + ("" if c["rms_px"] is None else f", RMS {c['rms_px']:.2f} px") + "\n" for c in res.cameras or [])
        + f"  time ms: {t}"
    )


def _camera(args, Camera):
    """The camera of --camera or of --camera-k and --image-size, with
    --height-m, --pitch-deg and --roll-deg; UsageError for a missing part;
    a value of those flags out of range is a CameraError naming the flag."""
    from linemap.camera import naming_flags

    flags = {"height_m": args.height_m is not None and "--height-m",
             "pitch_deg": args.pitch_deg is not None and "--pitch-deg",
             "roll_deg": getattr(args, "roll_deg", None) is not None and "--roll-deg"}
    with naming_flags(flags):
        return _camera_of_flags(args, Camera)


def _camera_of_flags(args, Camera):
    """:func:`_camera`'s work: a camera file with its overrides, or --camera-k's camera."""
    if args.camera:
        if args.image_size:
            raise UsageError("--image-size goes with --camera-k (a camera file holds its size)")
        _input_file(args.camera, "camera file")
        return Camera.load(args.camera, args.height_m, args.pitch_deg, getattr(args, "roll_deg", None))
    from linemap.camera_files import camera_from_k

    try:
        k = tuple(float(v) for v in args.camera_k.split(","))
    except ValueError:
        k = ()
    if len(k) != 4:
        raise UsageError(f"--camera-k takes FX,FY,CX,CY (pixels), got '{args.camera_k}'")
    try:
        size = tuple(int(v) for v in (args.image_size or "").lower().split("x"))
    except ValueError:
        size = ()
    if len(size) != 2:
        raise UsageError("--camera-k needs --image-size WxH (pixels, e.g. 640x480)")
    if args.height_m is None:
        raise UsageError("--camera-k needs --height-m (the camera's height above the floor, metres)")
    return camera_from_k(k, size, args.height_m, 0.0 if args.pitch_deg is None else args.pitch_deg,
                         roll_deg=getattr(args, "roll_deg", None))


def run_localize(args) -> int:
    import matcher

    from linemap.camera import Camera

    from matcher import cli_rig

    cli_rig.check_sources(args)
    prior = _prior_options(args)
    tol = _tolerances(args)
    if args.search is not None:
        tol = replace(tol or matcher.Tolerances(), search=args.search)
    _map_input(args.map)
    if cli_rig.rig_requested(args):
        linemap = cli_rig.one_floor(matcher.load_map(args.map), args.storey)
        rig, lines = cli_rig.rig_frame(args, _read_lines, _read_image)
        res = cli_rig.localize_frame(args, linemap, rig, lines, prior, tol)
        print(json.dumps(res.to_dict()) if args.json else _human(res, sum(len(x) for x in lines)))
        return EXIT_OK if res else EXIT_NOT_FOUND
    camera = _camera(args, Camera)
    linemap = matcher.load_map(args.map)
    scope = _storey_scope(linemap, args.storey, lost=prior is None)
    lines = _read_lines(args.lines[0]) if args.lines else _read_image(args.image[0], camera)
    if prior is None:
        one = isinstance(scope, matcher.Storey)  # lost mode on one storey of a building
        res = matcher.localize_global(scope.map if one else scope, camera, lines, tolerances=tol,
                                      progress=_region_progress if sys.stderr.isatty() else None)
        res = replace(res, storey=scope.name) if one else res
    else:
        res = matcher.localize(linemap, camera, lines, *prior, tolerances=tol, storey=args.storey)
    if args.json:
        print(json.dumps(res.to_dict()))
    else:
        print(_human(res, len(lines)))
    return EXIT_OK if res else EXIT_NOT_FOUND


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    # '--prior -1.5,2,30': a negative X would read as an option.
    args = parser.parse_args(join_negative_values(sys.argv[1:] if argv is None else list(argv), ("--prior",)))
    try:
        if args.command == "track":
            from matcher.cli_track import run_track

            return run_track(args)
        return run_localize(args)
    except StoreyNeeded as exc:  # the library's message names storey=NAME: here the flag is typed
        return _fail(str(exc.naming("--storey NAME")))
    except InputError as exc:  # UsageError, CameraError, LmapError, BagError and the input checks
        return _fail(str(exc))
    except BrokenPipeError:  # the reader went away (`matcher localize ... | head -1`); before OSError
        # Point stdout at devnull so the interpreter's final flush stays quiet.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except OSError as exc:
        return _fail(f"{getattr(exc, 'filename', '') or ''}: {exc.strerror or exc}".lstrip(": "))
    except MemoryError:
        return _fail(OUT_OF_MEMORY)
    except Exception as exc:  # noqa: BLE001 - anything else is a bug of ours, said to be one
        return report_bug("matcher", exc, args.debug)


def _fail(message: str) -> int:
    print(f"matcher: error: {message}", file=sys.stderr)
    return EXIT_USAGE


if __name__ == "__main__":
    raise SystemExit(main())
