"""Import options shared by ``build``, ``preview``, ``extrude`` and ``view --plan``.

One definition, so every command that reads a plan accepts the same flags
with the same defaults (those of :class:`~mapkit.options.BuildOptions`).
"""

from __future__ import annotations

from mapkit.errors import MapkitError
from mapkit.options import BuildOptions


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
    g.add_argument("--up", choices=("z", "y"), default=d.up, help="mesh up axis (glTF is y-up; default z)")
    g = p.add_argument_group("reconstruction")
    g.add_argument("--wall-height", type=float, default=d.wall_height, metavar="M", help=f"wall (ceiling) height (default {d.wall_height})")
    g.add_argument("--door-height", type=float, default=d.door_height, metavar="M", help=f"door head height (default {d.door_height})")
    g.add_argument("--window-sill", type=float, default=d.window_sill, metavar="M", help=f"window sill height (default {d.window_sill})")
    g.add_argument("--window-head", type=float, default=d.window_head, metavar="M", help=f"window head height (default {d.window_head})")
    g.add_argument("--robot-radius", type=float, default=d.robot_radius, metavar="M", help=f"keep the camera this far from walls (default {d.robot_radius})")
    g.add_argument("--max-wall-thickness", type=float, default=d.max_wall_thickness, metavar="M", help=f"thicker double lines are not walls (default {d.max_wall_thickness})")


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
        wall_height=args.wall_height,
        door_height=args.door_height,
        window_sill=args.window_sill,
        window_head=args.window_head,
        robot_radius=args.robot_radius,
        max_wall_thickness=args.max_wall_thickness,
    )
