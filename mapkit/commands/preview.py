"""``mapkit preview PLAN -o preview.png``: a picture of what the importer understood."""

from __future__ import annotations

HELP = "draw what was understood of a plan or mesh (walls, doors, windows, free space) as a PNG"


def add_arguments(p) -> None:
    from mapkit.commands._import_args import add_import_arguments

    p.add_argument("plan", metavar="PLAN", help="DXF plan or mesh")
    p.add_argument("-o", "--output", required=True, metavar="PREVIEW.png",
                   help="PNG file to write (an IFC model without --storey: PREVIEW-<storey>.png per storey)")
    p.add_argument("--dpi", type=int, default=150, help="resolution of the PNG (default 150)")
    add_import_arguments(p)


def run(args) -> int:
    import sys
    from pathlib import Path

    from mapkit.commands._import_args import import_options_from_args, output_file
    from mapkit.errors import InconsistentDrawingError, MapkitError, NoFreeSpaceError
    from mapkit.importers import load_scene
    from mapkit.preview import render_preview

    options = import_options_from_args(args)
    out = output_file(args.output, (".png",), [args.plan])
    if not 20 <= args.dpi <= 1200:
        raise MapkitError(f"--dpi must be between 20 and 1200, got {args.dpi}")
    if Path(args.plan).suffix.lower() == ".ifc" and options.floor_name is None:
        return _preview_storeys(Path(args.plan), out, options, args.dpi)
    try:
        scene = load_scene(args.plan, options)
    except (NoFreeSpaceError, InconsistentDrawingError) as exc:
        if exc.scene is None:
            raise
        # The preview is where a user sees why: draw what was understood.
        print(f"mapkit: warning: {exc}", file=sys.stderr)
        scene = exc.scene
    render_preview(scene, out, title=Path(args.plan).name, dpi=args.dpi)
    doors = sum(o.kind == "door" for o in scene.openings)
    windows = sum(o.kind == "window" for o in scene.openings)
    layers = scene.info.get("layers", {})
    used = "; ".join(f"{role}: {', '.join(names)}" for role, names in layers.items() if names and role != "ignored")
    print(
        f"wrote {out}: walls {scene.walls.area:.1f} m², free space {scene.free_space.area:.1f} m², "
        f"{doors} doors, {windows} windows" + (f" ({used})" if used else "")
    )
    return 0


def _preview_storeys(path, out, options, dpi: int) -> int:
    """One PNG per storey of an IFC model: ``OUT-<storey>.png`` beside ``out``."""
    from mapkit.building import storey_file_names
    from mapkit.errors import MapkitError
    from mapkit.importers.ifc import load_building
    from mapkit.preview import render_preview

    if not path.is_file():
        raise MapkitError(f"{path}: no such file; check the path")
    building = load_building(path, options)
    names = storey_file_names([s.name for s in building.storeys])
    for k, storey in enumerate(building.storeys):
        png = out.with_name(f"{out.stem}-{names[k][:-len('.lmap')]}.png")
        try:
            scene = building.scene(k, options)
        except MapkitError as exc:
            scene = getattr(exc, "scene", None)
            if scene is None:
                print(f"{storey.name}: nothing to draw ({exc})")
                continue
        render_preview(scene, png, title=f"{path.name}: {storey.name}", dpi=dpi)
        doors = sum(o.kind == "door" for o in scene.openings)
        windows = sum(o.kind == "window" for o in scene.openings)
        print(f"wrote {png}: walls {scene.walls.area:.1f} m², free space {scene.free_space.area:.1f} m², "
              f"{doors} doors, {windows} windows")
    return 0
