"""Import options shared by ``build``, ``preview``, ``extrude`` and ``view --plan``.

One definition, so every command that reads a plan accepts the same flags
with the same defaults (those of :class:`~mapkit.options.BuildOptions`),
and one check of the output file every command that writes one makes.
"""

from __future__ import annotations

from pathlib import Path

from mapkit.errors import MapkitError
from mapkit.options import BuildOptions


def add_float_options(group, defaults, options, metavar: str = "M") -> None:
    """Add float flags ``--name`` that default to the same-named field of
    ``defaults`` (a :class:`~mapkit.options.BuildOptions`); each help text
    ends with that default. ``options``: (flag, help text) pairs."""
    for flag, text in options:
        default = getattr(defaults, flag.lstrip("-").replace("-", "_"))
        group.add_argument(flag, type=float, default=default, metavar=metavar, help=f"{text} (default {default})")


def output_file(path, suffixes, inputs=()) -> Path:
    """``path`` as a Path once it ends in one of ``suffixes`` (lower case,
    with the dot), a file can be written there and it is none of the
    ``inputs``; else a one-line error."""
    from linemap.atomic import check_output_path

    out = Path(path)
    if out.suffix.lower() not in suffixes:
        wanted = suffixes[0] if len(suffixes) == 1 else "one of " + ", ".join(suffixes)
        raise MapkitError(f"output must end in {wanted}, got '{out.name}'")
    return check_output_path(out, inputs)


def add_import_arguments(p) -> None:
    """Add the plan/mesh import flags to an argparse parser."""
    d = BuildOptions()
    g = p.add_argument_group("import")
    g.add_argument("--units", metavar="UNIT", help="drawing units, overriding the file's: m, cm, mm, in, ft, ... ($INSUNITS for DXF)")
    g.add_argument("--scale", type=float, default=d.scale, help="extra scale factor after unit conversion (default 1)")
    g.add_argument("--walls", action="append", default=[], metavar="GLOB", help="layer(s) holding walls and columns (repeatable; default: guessed from names)")
    g.add_argument("--doors", action="append", default=[], metavar="GLOB", help="layer(s) holding doors (repeatable)")
    g.add_argument("--windows", action="append", default=[], metavar="GLOB", help="layer(s) holding windows or glass (repeatable)")
    g.add_argument("--floor", action="append", default=[], metavar="GLOB", help="layer(s) outlining the floor of an open plan (repeatable)")
    g.add_argument("--ignore", action="append", default=[], metavar="GLOB", help="layer(s) to leave out (repeatable)")
    g.add_argument("--floor-name", metavar="NAME",
                   help="floor to build of a tour with several (ZInD: floor_01, ...; default the first, with a warning)")
    g.add_argument("--up", choices=("auto", "z", "y"), default=d.up,
                   help="mesh up axis (default auto: glTF's y-up, z for the other formats; a glTF stored z-up is told by its faces)")
    g.add_argument("--max-entities", type=int, default=d.max_entities, metavar="N",
                   help=f"most DXF entities taken, blocks and MINSERT arrays expanded (default {d.max_entities})")
    add_float_options(p.add_argument_group("reconstruction"), d, [
        ("--wall-height", "wall (ceiling) height"),
        ("--door-height", "door head height"),
        ("--window-sill", "window sill height"),
        ("--window-head", "window head height"),
        ("--robot-radius", "keep the camera this far from walls"),
        ("--max-wall-thickness", "thicker double lines are not walls"),
    ])


def import_options_from_args(args) -> BuildOptions:
    """BuildOptions holding the import flags of ``args`` (other fields default)."""
    if args.units is not None:
        from mapkit.units import canonical_units

        args.units = canonical_units(args.units)  # one-line error for unknown units
    if not (args.scale > 0):
        raise MapkitError(f"--scale must be positive, got {args.scale}")
    for name in ("wall_height", "door_height", "window_head", "max_wall_thickness"):
        if not getattr(args, name) > 0:
            raise MapkitError(f"--{name.replace('_', '-')} must be positive, got {getattr(args, name)}")
    if not args.max_entities > 0:
        raise MapkitError(f"--max-entities must be a positive number, got {args.max_entities}")
    for name in ("robot_radius", "window_sill"):
        if not getattr(args, name) >= 0:
            raise MapkitError(f"--{name.replace('_', '-')} must be >= 0 metres, got {getattr(args, name)}")
    return BuildOptions(
        units=args.units,
        scale=args.scale,
        walls=list(args.walls),
        doors=list(args.doors),
        windows=list(args.windows),
        ignore=list(args.ignore),
        floor=list(args.floor),
        up=args.up,
        floor_name=args.floor_name,
        wall_height=args.wall_height,
        door_height=args.door_height,
        window_sill=args.window_sill,
        window_head=args.window_head,
        robot_radius=args.robot_radius,
        max_wall_thickness=args.max_wall_thickness,
        max_entities=args.max_entities,
    )
