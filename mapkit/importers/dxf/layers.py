"""Layers of a DXF drawing: entity counts and the role each one plays."""

from __future__ import annotations

from collections import Counter

from mapkit.errors import MapkitError, NoWallsError
from mapkit.importers.dxf.entities import SILENT
from mapkit.importers.dxf.read import model_space
from mapkit.importers.dxf.layer_roles import assign_roles, unmatched_globs
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
    """Role of every layer (see :func:`mapkit.importers.dxf.layer_roles.assign_roles`) and warnings.

    When no wall layer is named or recognised but exactly one layer of
    unknown role holds linework, that layer is taken as the walls (simple
    drawings keep everything on one layer). Raises :class:`NoWallsError`
    listing the layers otherwise, and :class:`MapkitError` for globs that
    match no layer.
    """
    floor = list(getattr(options, "floor", []) or [])
    missing = unmatched_globs(
        counts, walls=options.walls, doors=options.doors, windows=options.windows, ignore=options.ignore, floor=floor
    )
    if missing:
        raise MapkitError(f"{', '.join(missing)} matches no layer; layers are: {_listing(counts)}")
    roles = assign_roles(counts, options.walls, options.doors, options.windows, options.ignore, floor)
    warnings: list[str] = []
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
    return roles, warnings


def _listing(counts: dict[str, Counter]) -> str:
    names = [name for name, c in counts.items() if sum(c.values())] or list(counts)
    shown = ", ".join(f"'{n}'" for n in sorted(names)[:30])
    return shown + (f" (+{len(names) - 30} more)" if len(names) > 30 else "")
