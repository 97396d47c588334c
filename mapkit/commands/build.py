"""``mapkit build PLAN -o OUT.lmap``: the main job, plan, mesh or ZInD annotations in, map out."""

from __future__ import annotations

import sys

from mapkit.errors import MapkitError

HELP = "build a .lmap map from a DXF floor plan, a 3D mesh, 3D segments (.csv, .json) or ZInD annotations"


def add_arguments(p) -> None:
    from mapkit.commands._import_args import add_float_options, add_import_arguments
    from mapkit.options import BuildOptions
    from mapkit.parallel import MAX_DEFAULT_JOBS

    d = BuildOptions()
    p.add_argument("plan", metavar="PLAN",
                   help="DXF plan, mesh (.obj .ply .stl .glb .gltf .off), 3D segments (.csv, or .json with "
                        "\"segments\") or ZInD zind_data.json")
    p.add_argument("-o", "--output", required=True, metavar="OUT.lmap", help="map file to write")
    add_import_arguments(p)
    g = p.add_argument_group("camera (what 'visible' means)")
    g.add_argument("--camera", metavar="CAM.json", help="camera.json: intrinsics, height_m, pitch_deg")
    g.add_argument("--camera-height", type=float, metavar="M", help=f"camera height above the floor (default {d.camera['height_m']})")
    g.add_argument("--pitch", type=float, metavar="DEG", help=f"camera pitch, positive looking down (default {d.camera['pitch_deg']})")
    g.add_argument("--hfov", type=float, metavar="DEG", help="horizontal field of view of an ideal camera (default 70)")
    g.add_argument("--image-size", metavar="WxH", help="image size in pixels with --hfov (default 640x480)")
    g = p.add_argument_group("edges and visibility")
    add_float_options(g, d, [("--min-edge-length", "drop shorter edges")])
    add_float_options(g, d, [("--crease-deg", "mesh feature-edge angle")], metavar="DEG")
    add_float_options(g, d, [
        ("--max-range", "farthest visible distance"),
        ("--min-visible-length", "shortest contiguous visible piece that counts"),
        ("--eps", "region lists cover everything visible within this distance"),
    ])
    g.add_argument("--max-floor-area", type=float, default=d.max_floor_area, metavar="M2",
                   help=f"largest floor a map is built for, square metres, bounding box of the free space "
                        f"(default {d.max_floor_area:g}; the region builder's time and memory grow with it)")
    g.add_argument("--max-sight-work", type=float, default=d.max_sight_work, metavar="N",
                   help=f"most sight tests of the region builder per square metre of free space (default "
                        f"{d.max_sight_work:g}; buildings need under 5000, walls tangled by faces crossing the "
                        f"building far more)")
    g.add_argument("--merge-growth", type=float, default=d.merge_growth, metavar="F", help=f"merge neighbouring regions while the mean list grows by at most this fraction (default {d.merge_growth}; 0: tightest lists, more regions)")
    p.add_argument("-j", "--jobs", type=int, default=d.jobs, metavar="N",
                   help=f"threads for the region stage's geometry work (default {d.jobs}: the cores available, "
                        f"at most {MAX_DEFAULT_JOBS}; 1: one thread); the map is the same byte for byte")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")


def options_from_args(args):
    """BuildOptions from parsed arguments (import options, camera, visibility)."""
    from linemap.camera import Camera

    from mapkit.commands._import_args import import_options_from_args

    o = import_options_from_args(args)
    o.camera_from_source = not (args.camera or args.camera_height is not None)
    if args.camera:
        if any(v is not None for v in (args.camera_height, args.pitch, args.hfov, args.image_size)):
            raise MapkitError("--camera already sets the camera; drop --camera-height/--pitch/--hfov/--image-size")
        o.camera = Camera.load(args.camera).to_dict()
    else:
        cam = dict(o.camera)
        if args.camera_height is not None:
            cam["height_m"] = args.camera_height
        if args.pitch is not None:
            cam["pitch_deg"] = args.pitch
        if args.hfov is not None or args.image_size is not None:
            w, h = _image_size(args.image_size or f"{cam['width']}x{cam['height']}")
            hfov = args.hfov if args.hfov is not None else 70.0
            c = Camera.from_fov(hfov, w, h, cam["height_m"], cam["pitch_deg"])
            cam = c.to_dict()
        o.camera = Camera.from_dict(cam).to_dict()  # validates
    o.min_edge_length = args.min_edge_length
    o.crease_deg = args.crease_deg
    o.max_range = args.max_range
    o.min_visible_length = args.min_visible_length
    o.eps = args.eps
    o.merge_growth = args.merge_growth
    if not args.max_floor_area > 0:
        raise MapkitError(f"--max-floor-area must be a positive number of square metres, got {args.max_floor_area}")
    o.max_floor_area = args.max_floor_area
    if not args.max_sight_work > 0:
        raise MapkitError(f"--max-sight-work must be a positive number, got {args.max_sight_work}")
    o.max_sight_work = args.max_sight_work
    o.jobs = args.jobs
    return o


def _image_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise MapkitError(f"--image-size expects WIDTHxHEIGHT in pixels (e.g. 640x480), got '{text}'") from None
    if w <= 0 or h <= 0:
        raise MapkitError(f"--image-size must be positive, got '{text}'")
    return w, h


def run(args) -> int:
    from linemap.lmap import save_map
    from mapkit.commands._import_args import output_file
    from mapkit.pipeline import build_map

    options = options_from_args(args)
    out = output_file(args.output, (".lmap",), [args.plan])
    linemap, report = build_map(args.plan, options, progress=not args.quiet and sys.stderr.isatty())
    size = save_map(out, linemap)
    if not args.quiet:
        c = report.counts
        t = " ".join(f"{k} {v:.2f}s" for k, v in report.seconds.items())
        print(
            f"wrote {out}: {c['segments']} segments, {c['regions']} regions, "
            f"mean list {c['mean_list_length']:.1f}, {size / 1024:.1f} KiB  ({t})"
        )
    return 0
