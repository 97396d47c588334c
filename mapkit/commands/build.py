"""``mapkit build PLAN -o OUT.lmap``: the main job, plan, mesh, ZInD annotations or IFC model in, map out
(an IFC model of several storeys: ``-o DIR``, a map per storey and the building manifest).
``mapkit build A.dxf B.dxf ... -o DIR``: many builds at once as Dask tasks (:mod:`mapkit.batch`)."""

from __future__ import annotations

import sys

from mapkit.errors import MapkitError

HELP = "build a .lmap map from a DXF floor plan, a 3D mesh, 3D segments (.csv, .json), ZInD annotations or an IFC model (a map per storey)"


def add_arguments(p) -> None:
    from mapkit.commands._import_args import add_import_arguments, add_option_flags
    from mapkit.options import BUILD_GROUPS, DEFAULT_HFOV_DEG, DEFAULT_IMAGE_SIZE, default_camera

    p.add_argument("plans", nargs="+", metavar="PLAN",
                   help="DXF plan, mesh (.obj .ply .stl .glb .gltf .off), 3D segments (.csv, or .json with "
                        "\"segments\"), ZInD zind_data.json or IFC model (.ifc); several: built at once on Dask "
                        "into -o DIR")
    p.add_argument("-o", "--output", required=True, metavar="OUT.lmap",
                   help="map file to write; for an IFC model of several storeys a folder: DIR/<storey>.lmap and "
                        "DIR/building.json (--storey NAME with OUT.lmap: that storey); for several inputs a folder "
                        "(made if missing): DIR/<stem>.lmap per plan, DIR/<stem>/ per IFC model")
    g = p.add_argument_group("many inputs, or a large floor's tiles, at once (Dask; pip install 'mapkit[dask]')")
    where = g.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help="worker processes of a local Dask cluster, one build each at a time (default: the "
                            "cores available, at most one per input); with one input and -o OUT.lmap, one tile of a "
                            "floor built in tiles (--memory-budget) each")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="run the builds (with one input and -o OUT.lmap: its tiles) on the running Dask "
                            "cluster at ADDRESS (tcp://HOST:PORT); its workers must see the inputs and DIR at the "
                            "same paths")
    add_import_arguments(p)
    cam = default_camera()
    g = p.add_argument_group("camera (what 'visible' means)")
    g.add_argument("--camera", metavar="CAM.json", help="camera.json: intrinsics, height_m, pitch_deg")
    g.add_argument("--camera-height", type=float, metavar="M",
                   help=f"camera height above the floor (default {cam['height_m']:g})")
    g.add_argument("--pitch", type=float, metavar="DEG",
                   help=f"camera pitch, positive looking down (default {cam['pitch_deg']:g})")
    g.add_argument("--hfov", type=float, metavar="DEG",
                   help=f"horizontal field of view of an ideal camera (default {DEFAULT_HFOV_DEG:g})")
    g.add_argument("--image-size", metavar="WxH",
                   help="image size in pixels with --hfov (default {}x{})".format(*DEFAULT_IMAGE_SIZE))
    add_option_flags(p, BUILD_GROUPS)
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")


def options_from_args(args):
    """BuildOptions from parsed arguments (import options, camera, visibility)."""
    from mapkit.commands import _import_args
    from mapkit.options import BUILD_GROUPS, IMPORT_GROUPS

    return _import_args.options_from_args(args, IMPORT_GROUPS + BUILD_GROUPS, camera=_camera_from_args(args),
                                          camera_from_source=not (args.camera or args.camera_height is not None))


def _camera_from_args(args) -> dict:
    """The camera.json shape the camera flags ask for: a camera file, or
    the default camera with the height, pitch, field of view and image size
    given."""
    from linemap.camera import Camera, naming_flags

    from mapkit.options import DEFAULT_HFOV_DEG, default_camera

    if args.camera:
        if any(v is not None for v in (args.camera_height, args.pitch, args.hfov, args.image_size)):
            raise MapkitError("--camera already sets the camera; drop --camera-height/--pitch/--hfov/--image-size")
        return Camera.load(args.camera).to_dict()
    flags = {"height_m": args.camera_height is not None and "--camera-height",
             "pitch_deg": args.pitch is not None and "--pitch", "hfov_deg": args.hfov is not None and "--hfov"}
    with naming_flags(flags):  # "--camera-height must be ...", not the camera field it sets
        cam = default_camera()
        if args.camera_height is not None:
            cam["height_m"] = args.camera_height
        if args.pitch is not None:
            cam["pitch_deg"] = args.pitch
        if args.hfov is not None or args.image_size is not None:
            w, h = _image_size(args.image_size or f"{cam['width']}x{cam['height']}")
            hfov = args.hfov if args.hfov is not None else DEFAULT_HFOV_DEG
            cam = Camera.from_fov(hfov, w, h, cam["height_m"], cam["pitch_deg"]).to_dict()
        return Camera.from_dict(cam).to_dict()  # validates


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
    one_map = len(args.plans) == 1 and args.output.lower().endswith(".lmap")
    if not one_map and (len(args.plans) > 1 or args.workers is not None or args.scheduler is not None):
        return _run_batch(args, options)
    args.plan = args.plans[0]
    if _is_building(args):
        return _run_building(args, options)
    out = output_file(args.output, (".lmap",), [args.plan])
    linemap, report = build_map(args.plan, options, progress=not args.quiet and sys.stderr.isatty(),
                                runner=_tile_runner(args))
    size = save_map(out, linemap)
    if not args.quiet:
        c = report.counts
        t = " ".join(f"{k} {v:.2f}s" for k, v in report.seconds.items())
        tiles = f", regions in {c['tiles']} tiles" if "tiles" in c else ""
        print(
            f"wrote {out}: {c['segments']} segments, {c['regions']} regions, "
            f"mean list {c['mean_list_length']:.1f}, {size / 1024:.1f} KiB{tiles}  ({t})"
        )
    return 0


def _tile_runner(args):
    """One map with --workers or --scheduler: its tiles (if it is built in
    tiles) as Dask tasks; None: in this process."""
    if args.workers is None and args.scheduler is None:
        return None
    if args.workers is not None and args.workers < 1:
        raise MapkitError(f"--workers must be at least 1, got {args.workers}")
    try:
        import distributed  # noqa: F401 - only to say what to install
    except ImportError:
        raise MapkitError("--workers and --scheduler need Dask: pip install 'mapkit[dask]'") from None
    from mapkit.tile_runner import DaskTiles

    return DaskTiles(args.workers, args.scheduler)


def _is_building(args) -> bool:
    """An IFC model built into a folder: every storey's map and the manifest."""
    from pathlib import Path

    return Path(args.plan).suffix.lower() == ".ifc" and Path(args.output).suffix.lower() != ".lmap"


def _run_building(args, options) -> int:
    from pathlib import Path

    from mapkit.building import build_building, write_building

    if options.floor_name is not None:
        raise MapkitError(f"--storey builds one storey into one map: give -o OUT.lmap, not the folder '{args.output}'")
    plan = Path(args.plan)
    if not plan.is_file():
        raise MapkitError(f"{plan}: no such file; check the path")
    result = build_building(plan, options, progress=not args.quiet and sys.stderr.isatty())
    manifest = write_building(result, args.output)
    if not args.quiet:
        print(f"read {plan.name} in {result.import_seconds:.2f}s")
        for o in result.storeys:
            if o.map is None:
                print(f"  {o.name}: no map ({o.why})")
                continue
            c = o.report.counts
            print(f"  {o.name}: {o.file_name}: {c['segments']} segments, {c['regions']} regions, "
                  f"mean list {c['mean_list_length']:.1f}  ({o.seconds:.2f}s)")
        print(f"wrote {manifest}")
    return 0


def _run_batch(args, options) -> int:
    """Several inputs (or --workers/--scheduler): each built by a Dask task into
    ``-o DIR``; the unchanged skipped; every failure one line, exit 2 (3 for a bug)."""
    from pathlib import Path

    from mapkit import batch

    if args.workers is not None and args.workers < 1:
        raise MapkitError(f"--workers must be at least 1, got {args.workers}")
    out = Path(args.output)
    if out.suffix.lower() == ".lmap":
        raise MapkitError(f"several inputs (or --workers/--scheduler) build into a folder: give -o DIR, not "
                          f"'{args.output}'")
    if out.exists() and not out.is_dir():
        raise MapkitError(f"{out}: exists and is not a folder; give a folder for the maps (-o DIR)")
    jobs = batch.plan_jobs(args.plans, out)
    todo = [j for j in jobs if not batch.is_up_to_date(j, options)]
    skipped = len(jobs) - len(todo)
    if todo:
        try:
            import distributed  # noqa: F401 - only to say what to install
        except ImportError:
            raise MapkitError("building several inputs at once needs Dask: pip install 'mapkit[dask]'") from None
        out.mkdir(parents=True, exist_ok=True)

    def say(result) -> None:
        if result.status == batch.BUILT and not args.quiet:
            shown = out / Path(result.output).name  # as the user wrote -o (the workers get absolute paths)
            print(f"wrote {shown}: {result.summary}  ({result.seconds:.2f}s)", flush=True)
        elif result.status == batch.FAILED:
            print(f"mapkit: error: {result.error}", file=sys.stderr, flush=True)

    results = batch.run_jobs(todo, options, workers=args.workers, scheduler=args.scheduler,
                             progress=not args.quiet and sys.stderr.isatty(), on_result=say)
    failed = [r for r in results if r.status == batch.FAILED]
    bugs = [r for r in results if r.status == batch.BUG]
    for r in bugs:
        print(f"mapkit: internal error: {r.error} -- this is a bug, please report it (rerun that input on its own "
              "with --debug for the traceback)", file=sys.stderr)
    if not args.quiet:
        built = len(results) - len(failed) - len(bugs)
        print(f"built {built}, skipped {skipped} unchanged, failed {len(failed) + len(bugs)} of {len(jobs)} inputs")
    if bugs:
        from linemap.errors import EXIT_BUG

        return EXIT_BUG
    return 2 if failed else 0
