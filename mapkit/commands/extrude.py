"""``mapkit extrude PLAN -o model.glb``: the 3D model a plan builds, for simulators and checks."""

from __future__ import annotations

from mapkit.errors import MapkitError

HELP = "write the 3D model (walls with door and window openings, floor) a plan builds"

#: Output suffix -> trimesh export type.
FORMATS = {".glb": "glb", ".obj": "obj", ".ply": "ply", ".stl": "stl"}


def add_arguments(p) -> None:
    from mapkit.commands._import_args import add_import_arguments

    p.add_argument("plan", metavar="PLAN", help="DXF plan (a mesh gives its walls at camera height as plain prisms)")
    p.add_argument("-o", "--output", required=True, metavar="MODEL", help=f"model to write ({' '.join(FORMATS)})")
    p.add_argument("--ceiling", action="store_true", help="add a ceiling slab on top of the walls")
    add_import_arguments(p)
    p.add_argument("-q", "--quiet", action="store_true", help="no summary line")


def run(args) -> int:
    from linemap.atomic import write_atomic
    from mapkit.commands._import_args import import_options_from_args, output_file
    from mapkit.extrude import scene_to_mesh
    from mapkit.importers import load_scene

    out = output_file(args.output, tuple(FORMATS), [args.plan])
    kind = FORMATS[out.suffix.lower()]
    options = import_options_from_args(args)
    scene = load_scene(args.plan, options)
    if scene.walls.is_empty:
        raise MapkitError(f"{args.plan}: no walls to extrude; check the layer choice with 'mapkit preview'")
    mesh = scene_to_mesh(scene, ceiling=args.ceiling, robot_radius=options.robot_radius)
    if kind == "glb":  # glTF's axes are +Y up: turned, so that viewers and simulators show it upright
        import numpy as np

        from mapkit.importers.mesh.load import Y_UP_TO_Z_UP

        turn = np.eye(4)
        turn[:3, :3] = Y_UP_TO_Z_UP.T
        mesh.apply_transform(turn)
    data = mesh.export(file_type=kind)
    write_atomic(out, data if isinstance(data, (bytes, str)) else bytes(data))
    if not args.quiet:
        print(
            f"wrote {out}: {len(mesh.faces)} triangles, walls {scene.wall_height:g} m high, "
            f"{len(scene.openings)} openings{', with ceiling' if args.ceiling else ''}"
        )
    return 0
