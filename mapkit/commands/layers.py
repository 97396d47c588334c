"""``mapkit layers PLAN``: every layer of a DXF plan, its entities and the role it gets."""

from __future__ import annotations

import json

HELP = ("list the layers of a DXF plan with entity counts and the role each is given (an IFC model: its storeys and "
        "element classes)")


def add_arguments(p) -> None:
    from mapkit.commands._import_args import add_import_arguments

    p.add_argument("plan", metavar="PLAN", help="DXF floor plan, or IFC model (.ifc)")
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    add_import_arguments(p)


def run(args) -> int:
    from pathlib import Path

    from mapkit.commands._import_args import import_options_from_args
    from mapkit.errors import MapkitError, NoWallsError
    from mapkit.importers.dxf.layers import layer_counts, resolve_roles, room_roles
    from mapkit.importers.dxf.read import read_dxf
    from mapkit.importers.dxf.layer_roles import assign_roles
    from mapkit.importers.dxf.swing_layer import adopt_swing_layer

    options = import_options_from_args(args)
    path = Path(args.plan)
    if path.is_dir():
        raise MapkitError(f"{path}: is a directory, expected a DXF file")
    if not path.is_file():
        raise MapkitError(f"{path}: no such file; check the path")
    if path.suffix.lower() == ".ifc":
        return _ifc_layers(path, args.json)
    if path.suffix.lower() != ".dxf":
        raise MapkitError(f"{path.name}: 'mapkit layers' reads DXF plans (.dxf), got a '{path.suffix}' file")
    doc, warnings = read_dxf(path)
    document = (doc, list(warnings))  # as read, for the plans below: the file is parsed once
    counts = layer_counts(doc)
    # Why a layer's role differs from what its name says (a plan drawn one layer per room).
    decided = room_roles(counts, assign_roles(counts, options.walls, options.doors, options.windows, options.ignore,
                                              list(getattr(options, "floor", []) or [])), options)
    try:
        roles, more = resolve_roles(counts, options)
        warnings += more
    except NoWallsError as exc:
        adopted = adopt_swing_layer(doc, counts, options)  # the layer of the door swings, as the build takes it
        if adopted is not None:
            roles = adopted.roles
            decided[adopted.layer] = adopted.why
            warnings.append(adopted.warning)
        else:
            # Listing the layers is how a user finds the wall layers: show them anyway.
            roles = assign_roles(counts, options.walls, options.doors, options.windows, options.ignore)
            warnings.append(str(exc))

    rows = [
        {
            "name": name,
            "role": {"ignore": "ignored", None: "unknown"}.get(roles.get(name), roles.get(name)),
            "entities": dict(sorted(c.items())),
            "total": sum(c.values()),
            "why": decided.get(name) if roles.get(name) == "walls" and name in decided
            else _why(name, roles.get(name), options),
        }
        for name, c in sorted(counts.items(), key=lambda kv: kv[0].casefold())
    ]
    plans = _plans(path, document, options, roles)
    if args.json:
        print(json.dumps({"file": path.name, "layers": rows, "plans": plans, "warnings": warnings}))
        return 0
    print(_table(rows))
    if len(plans) > 1:
        print(f"plans: {len(plans)} separate plans on the sheet, numbered for --plan (walls' extent, metres):")
        for p in plans:
            (x0, y0, x1, y1), n = p["bounds_m"], p["plan"]
            print(f"  #{n}  {x1 - x0:.1f} x {y1 - y0:.1f} m at ({x0:.1f}, {y0:.1f}), walls {p['wall_length_m']:.0f} m long"
                  + ("  (built by default)" if n == 1 else ""))
    for w in warnings:
        print(f"note: {w}")
    return 0


def _plans(path, document, options, roles) -> list[dict]:
    """The separate plans of the drawing's walls (:mod:`mapkit.importers.dxf.sheets`), [] without walls;
    ``document`` is the ``(ezdxf document, warnings)`` already read of ``path``."""
    import logging

    from mapkit.errors import NoWallsError
    from mapkit.importers.dxf import load_drawing

    if "walls" not in roles.values():
        return []
    logging.getLogger("mapkit").disabled = True  # the build's warnings are not this listing's
    try:
        _, info = load_drawing(path, options, document)
    except NoWallsError:  # a wall layer by name that holds no linework: the listing's note says so
        return []
    finally:
        logging.getLogger("mapkit").disabled = False
    return info.get("plans", [])


def _why(name: str, role: str | None, options) -> str:
    """Why a layer has its role: the option that named it, or the word of its name."""
    from mapkit.importers.dxf.layer_roles import _matches, explain_role

    for opt in ("ignore", "walls", "doors", "windows", "floor"):
        globs = getattr(options, opt, None) or []
        if _matches(name, globs):
            return f"--{opt} {next(g for g in globs if _matches(name, [g]))}"
    guessed, reason = explain_role(name)
    if role == guessed:
        return reason
    if role == "ignore" and guessed is not None:
        return f"{reason}; other layers were named with --{guessed}"
    if role == "walls":
        return "the only layer with linework"
    return reason


def _table(rows: list[dict]) -> str:
    """Aligned text table: layer, role, total, entities per type, why the role."""
    header = ("LAYER", "ROLE", "COUNT", "ENTITIES", "WHY")
    body = [
        (r["name"], r["role"], str(r["total"]), ", ".join(f"{k} {v}" for k, v in r["entities"].items()) or "-", r["why"])
        for r in rows
    ]
    widths = [max(len(row[i]) for row in [header, *body]) for i in range(4)]
    lines = []
    for row in [header, *body]:
        lines.append(f"{row[0]:<{widths[0]}}  {row[1]:<{widths[1]}}  {row[2]:>{widths[2]}}  {row[3]:<{widths[3]}}  {row[4]}")
    return "\n".join(lines)


#: What each role of :data:`mapkit.importers.ifc.read.ROLES` becomes in a storey's map.
IFC_BECOMES = {
    "wall": "walls (footprint seen from above)",
    "door": "door gap in its wall, at its opening's heights",
    "window": "window gap in its wall, at its opening's sill and head",
    "opening": "the gap of a door or window (unfilled: a passage or hole)",
    "space": "free space",
    "slab": "free space where a storey has no spaces",
    "connection": "manifest connection; kept out of the free space",
}


def _ifc_layers(path, as_json: bool) -> int:
    """The storeys of an IFC model and the element classes of each, with what each becomes."""
    from mapkit.importers.ifc.read import LISTED_UNUSED, ROLES, count_roles, open_model

    model = open_model(path)
    storeys = []
    for s in model.storeys:
        counts = count_roles([e for v in s.elements.values() for e in v])
        storeys.append({"name": s.name, "elevation_m": round(s.elevation, 3),
                        "classes": {cls: counts[cls] for cls in ROLES if counts[cls]}})
    unused = {cls: model.class_counts[cls] for cls in LISTED_UNUSED if model.class_counts.get(cls)}
    becomes = {cls: IFC_BECOMES[role] for cls, role in ROLES.items()} | {cls: "not used" for cls in unused}
    if as_json:
        print(json.dumps({"file": path.name, "schema": model.schema, "storeys": storeys, "unused": unused,
                          "becomes": becomes}))
        return 0
    print(f"{path.name}: {model.schema}, {len(storeys)} storeys")
    for s in storeys:
        print(f"storey '{s['name']}' at {s['elevation_m']:g} m")
        for cls, n in s["classes"].items():
            print(f"  {cls:<20} {n:>4}  {becomes[cls]}")
    if unused:
        print("not used: " + ", ".join(f"{cls} {n}" for cls, n in unused.items()))
    return 0
