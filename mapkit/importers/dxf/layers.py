"""Layers of a DXF drawing: entity counts and the role each one plays."""

from __future__ import annotations

from collections import Counter

from mapkit.errors import MapkitError, NoWallsError
from mapkit.importers.dxf.entities import SILENT
from mapkit.importers.dxf.read import model_space
from mapkit.importers.dxf.layer_roles import _matches, assign_roles, unmatched_globs
from mapkit.importers.dxf.room_layers import room_outline_layers
from mapkit.options import BuildOptions


def layer_counts(doc) -> dict[str, Counter]:
    """Model-space entity counts per layer and type; layers of the layer table with none too."""
    counts: dict[str, Counter] = {layer.dxf.name: Counter() for layer in doc.layers}
    for entity in model_space(doc):
        counts.setdefault(entity.dxf.get("layer", "0"), Counter())[entity.dxftype()] += 1
    return counts


def _has_linework(counter: Counter) -> bool:
    return any(kind not in SILENT and n for kind, n in counter.items())


def resolve_roles(counts: dict[str, Counter], options: BuildOptions) -> tuple[dict[str, str | None], list[str]]:
    """Role of every layer and warnings; see :func:`resolve_layer_roles`."""
    roles, warnings, _ = resolve_layer_roles(counts, options)
    return roles, warnings


def resolve_layer_roles(counts: dict[str, Counter],
                        options: BuildOptions) -> tuple[dict[str, str | None], list[str], list[str]]:
    """Role of every layer (see :func:`mapkit.importers.dxf.layer_roles.assign_roles`), warnings, and the
    layers whose lines are the rooms' outlines (walls, that with the door lines enclose the rooms).

    Plans drawn one layer per room have their rooms' outlines as walls
    (:func:`room_roles`), with a warning. When no wall layer is named or recognised but
    exactly one layer of unknown role holds linework, that layer is taken
    as the walls (simple drawings keep everything on one layer). Raises :class:`NoWallsError`
    listing the layers otherwise (the importer then takes the layer of the
    door swings, :mod:`.swing_layer`, where one qualifies), and
    :class:`MapkitError` for globs that match no layer.
    """
    floor = list(getattr(options, "floor", []) or [])
    missing = unmatched_globs(
        counts, walls=options.walls, doors=options.doors, windows=options.windows, ignore=options.ignore, floor=floor
    )
    if missing:
        raise MapkitError(f"{', '.join(missing)} matches no layer; layers are: {_listing(counts)}")
    roles = assign_roles(counts, options.walls, options.doors, options.windows, options.ignore, floor)
    outlines = sorted(room_roles(counts, roles, options))
    roles.update({name: "walls" for name in outlines})
    warnings: list[str] = []
    if outlines:
        shown = ", ".join(f"'{n}'" for n in outlines[:5])
        shown += f" (+{len(outlines) - 5} more)" if len(outlines) > 5 else ""
        warnings.append(f"the rooms' outlines on {shown} (rooms drawn a layer each, or on layers named for spaces) "
                        f"are taken as the walls and, with the door lines, as the rooms (see 'mapkit layers PLAN'; "
                        f"--walls to choose)")
    wall_layers = [name for name, role in roles.items() if role == "walls" and _has_linework(counts[name])]
    if not wall_layers and not options.walls:
        unknown = [name for name, role in roles.items() if role is None and _has_linework(counts[name])]
        if len(unknown) == 1:
            roles[unknown[0]] = "walls"
            warnings.append(
                f"no layer is named like walls; using the only drawing layer '{unknown[0]}' as walls "
                f"(pass --walls to choose)"
            )
            wall_layers = unknown
    if not wall_layers and options.walls:  # the user named them: they hold no linework
        named = sorted(name for name, role in roles.items() if role == "walls")
        raise NoWallsError(
            f"the wall layers given ({', '.join(repr(n) for n in named)}) hold no lines or outlines, only "
            f"{', '.join(sorted({k for n in named for k in counts[n]})) or 'nothing'}; layers are "
            f"{_listing(counts)}; see 'mapkit layers PLAN'"
        )
    if not wall_layers:
        raise NoWallsError(
            f"no recognisable walls: layers are {_listing(counts)}; "
            f"name the wall layers with --walls (see 'mapkit layers PLAN')"
        )
    return roles, warnings, outlines


def room_roles(counts: dict[str, Counter], roles: dict[str, str | None], options: BuildOptions) -> dict[str, str]:
    """The layers whose role by name gives way to the rooms' outlines as
    walls (:mod:`mapkit.importers.dxf.room_layers`), and why each; none when
    the user named the wall layers."""
    if options.walls:
        return {}
    named = [*options.doors, *options.windows, *options.ignore, *(getattr(options, "floor", []) or [])]
    guessed = {name for name in counts if not _matches(name, named)}
    return room_outline_layers(counts, roles, guessed)


def _listing(counts: dict[str, Counter]) -> str:
    names = [name for name, c in counts.items() if sum(c.values())] or list(counts)
    shown = ", ".join(f"'{n}'" for n in sorted(names)[:30])
    return shown + (f" (+{len(names) - 30} more)" if len(names) > 30 else "")
