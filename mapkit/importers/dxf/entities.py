"""Flatten DXF model-space entities into :class:`~mapkit.importers.dxf.strokes.Stroke` objects.

Curves (arcs, circles, ellipses, splines, polyline bulges) become polylines
whose chords stay within ``CURVE_SAGITTA`` of the curve and turn by at most
``CURVE_STEP_DEG`` per step. Block inserts are expanded recursively with
their transforms (scale incl. mirroring, rotation, MINSERT arrays); block
content on layer 0 takes the layer of its INSERT, as CAD programs draw it.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Iterator

import numpy as np
from ezdxf import path as dxfpath

from mapkit.importers.dxf.strokes import Stroke
from mapkit.errors import MapkitError
from mapkit.tolerances import (
    CURVE_BEZIER_PER_TURN,
    CURVE_STEP_DEG,
    DXF_MAX_BLOCK_DEPTH,
    DXF_MAX_ENTITIES,
    PLAUSIBLE_EXTENT,
)

#: Entities that carry no building geometry: skipped without a word.
SILENT = frozenset(
    {
        "TEXT", "MTEXT", "ATTRIB", "ATTDEF", "DIMENSION", "ARC_DIMENSION", "LARGE_RADIAL_DIMENSION",
        "LEADER", "MULTILEADER", "MLEADER", "TOLERANCE", "POINT", "VIEWPORT", "WIPEOUT", "SEQEND",
        "IMAGE", "UNDERLAY", "PDFUNDERLAY", "DWFUNDERLAY", "DGNUNDERLAY", "OLE2FRAME", "XLINE", "RAY",
    }
)

#: Entities turned into outlines through ezdxf's path support.
PATH_TYPES = frozenset({"LINE", "LWPOLYLINE", "POLYLINE", "ARC", "CIRCLE", "ELLIPSE", "SPLINE"})

#: Entities whose outline is a solid fill.
FILL_TYPES = frozenset({"HATCH", "SOLID", "TRACE", "MPOLYGON"})

#: Entities expanded into simpler ones by ezdxf.
EXPAND_TYPES = frozenset({"INSERT", "MLINE"})

#: Least flattening steps per Bezier piece, so each step turns at most CURVE_STEP_DEG.
_MIN_SEGMENTS = math.ceil(360.0 / CURVE_BEZIER_PER_TURN / CURVE_STEP_DEG)


def flatten_entities(
    entities,
    factor: float,
    sagitta: float,
    layer_wanted: Callable[[str], bool],
    max_entities: int | None = None,
) -> tuple[list[Stroke], Counter]:
    """Strokes (in metres) of model-space ``entities`` on wanted layers.

    ``factor``: metres per drawing unit; ``sagitta``: chord tolerance in
    drawing units; ``layer_wanted(layer)`` says whether a layer's geometry is
    needed at all. Returns the strokes and a count of unsupported entity
    types that were skipped. An entity with a non-finite coordinate (a
    damaged file) is left out and counted as ``"<type> (non-finite
    coordinates, handle H on layer L)"``: its geometry would stall or break
    the plan's reconstruction. So is an outline larger than any building
    (its control points span more than ``PLAUSIBLE_EXTENT``'s upper bound, a
    damaged bulge or radius): flattened to ``sagitta`` it would take
    billions of points. More than ``max_entities`` entities with geometry
    (blocks and MINSERT arrays expanded; default ``DXF_MAX_ENTITIES``) is a
    :class:`MapkitError` naming ``--max-entities``, raised as soon as the
    count passes it.
    """
    limit = DXF_MAX_ENTITIES if max_entities is None else max_entities
    taken = 0
    max_span = PLAUSIBLE_EXTENT[1] / factor if factor > 0 else math.inf
    strokes: list[Stroke] = []
    skipped: Counter = Counter()
    groups: dict[tuple[int, int], int] = {}
    for index, entity in enumerate(entities):
        layer = entity.dxf.get("layer", "0")
        if not _finite_placement(entity):
            skipped[_left_out(entity, layer)] += 1
            continue
        if entity.dxftype() in EXPAND_TYPES:
            # Each top-level block insert (each MINSERT cell) is one group:
            # one door, one window, one column.
            items = _expand(entity, layer, 0, 0, skipped)
        else:
            items = iter([(entity, layer, None)])
        for sub, sub_layer, cell in items:
            if not layer_wanted(sub_layer) or sub.dxftype() in SILENT:
                continue
            taken += 1
            if taken > limit:
                raise MapkitError(f"the drawing holds more than {limit} entities with geometry (blocks and MINSERT "
                                  f"arrays expanded; DXF_MAX_ENTITIES): building it would take very long; raise "
                                  f"the limit with --max-entities if the plan is really that large")
            group = None if cell is None else groups.setdefault((index, cell), len(groups))
            for coords, closed, filled in _outlines(sub, sagitta, skipped, max_span):
                if coords is None:
                    skipped[_left_out(entity, layer, f"larger than {PLAUSIBLE_EXTENT[1]:g} m")] += 1
                    continue
                if not np.isfinite(coords).all():
                    skipped[_left_out(entity, layer)] += 1
                    continue
                strokes.append(Stroke(coords * factor, closed, filled, sub_layer, group))
    return strokes, skipped


def check_entity_count(entities, blocks, limit: int = DXF_MAX_ENTITIES) -> int:
    """The number of entities with geometry in ``entities`` once blocks and
    MINSERT arrays are expanded, counted from the block definitions without
    expanding anything (a MINSERT of 10^6 copies costs one multiplication);
    :class:`MapkitError` naming ``--max-entities`` as soon as it passes ``limit``."""
    memo: dict[str, int] = {}

    def block_count(name: str, depth: int) -> int:
        if name not in memo:
            memo[name] = 0  # a reference cycle counts as empty (the expansion skips it too)
            block = blocks.get(name) if depth <= DXF_MAX_BLOCK_DEPTH else None
            memo[name] = 0 if block is None else count(block, depth + 1)
        return memo[name]

    def count(items, depth: int) -> int:
        total = 0
        for e in items:
            kind = e.dxftype()
            if kind == "INSERT":
                copies = max(1, int(e.dxf.get("row_count", 1) or 1)) * max(1, int(e.dxf.get("column_count", 1) or 1))
                total += copies * block_count(e.dxf.get("name", ""), depth)
            elif kind not in SILENT:
                total += 1
            if total > limit:
                raise MapkitError(
                    f"the drawing holds more than {limit} entities with geometry (blocks and MINSERT arrays "
                    f"expanded; DXF_MAX_ENTITIES): building it would take very long; raise the limit with "
                    f"--max-entities if the plan is really that large")
        return total

    return count(entities, 0)


def _finite_placement(entity) -> bool:
    """False when an entity's placement points (insert, start, end, centre,
    vertices of a polyline) hold a NaN or an infinity."""
    try:
        for name in ("insert", "start", "end", "center"):
            if entity.dxf.hasattr(name):
                if not all(math.isfinite(v) for v in entity.dxf.get(name)):
                    return False
        for name in ("radius", "xscale", "yscale", "rotation"):
            if entity.dxf.hasattr(name) and not math.isfinite(float(entity.dxf.get(name))):
                return False
        if entity.dxftype() == "LWPOLYLINE":
            return bool(np.isfinite(np.asarray(entity.get_points("xy"), dtype=float)).all())
    except (TypeError, ValueError, AttributeError):
        return False
    return True


def _left_out(entity, layer: str, why: str = "non-finite coordinates") -> str:
    """The skipped-entities key of a damaged entity, naming it for the user."""
    handle = entity.dxf.get("handle", "?")
    return f"{entity.dxftype()} ({why}, handle {handle} on layer {layer})"


def _expand(entity, layer: str, cell: int, depth: int, skipped: Counter) -> Iterator[tuple[object, str, int]]:
    """Leaf entities of an INSERT/MLINE with their effective layers and MINSERT cell index."""
    if depth > DXF_MAX_BLOCK_DEPTH:
        skipped["INSERT (nested too deep)"] += 1
        return
    kind = entity.dxftype()
    if kind == "INSERT" and entity.mcount > 1:
        # MINSERT: one virtual insert per array cell.
        for i, sub in enumerate(entity.multi_insert()):
            yield from _expand(sub, layer, cell * entity.mcount + i if depth else i, depth + 1, skipped)
        return
    try:
        children = list(entity.virtual_entities())
    except Exception:  # noqa: BLE001 - ezdxf raises many types for broken blocks
        skipped[f"{kind} (broken)"] += 1
        return
    for child in children:
        child_layer = child.dxf.get("layer", "0")
        # Layer 0 inside a block means "the layer of the insert".
        effective = layer if child_layer == "0" else child_layer
        if child.dxftype() in EXPAND_TYPES:
            yield from _expand(child, effective, cell, depth + 1, skipped)
        else:
            yield child, effective, cell


def _outlines(entity, sagitta: float, skipped: Counter,
              max_span: float = math.inf) -> Iterator[tuple[np.ndarray | None, bool, bool]]:
    """(coords (N, 2) in drawing units, closed, filled) for each outline of
    an entity; coords None for an outline whose control points span more
    than ``max_span`` drawing units (not flattened)."""
    kind = entity.dxftype()
    if kind in SILENT:
        return
    if kind in PATH_TYPES:
        filled = False
        try:
            paths = [dxfpath.make_path(entity, segments=CURVE_BEZIER_PER_TURN)]
        except Exception:  # noqa: BLE001 - degenerate geometry (zero-radius arc, bad spline)
            skipped[f"{kind} (degenerate)"] += 1
            return
    elif kind in ("HATCH", "MPOLYGON"):
        # Solid or patterned, a hatch on a wall layer fills the wall's section;
        # hatches on floor layers never get here (their role is not walls).
        filled = True
        paths = list(dxfpath.from_hatch(entity))
    elif kind in ("SOLID", "TRACE"):
        filled = True
        paths = [dxfpath.make_path(entity)]
    else:
        skipped[kind] += 1
        return
    for p in paths:
        subs = p.sub_paths() if p.has_sub_paths else [p]
        for sub in subs:
            cv = np.array([(v.x, v.y) for v in sub.control_vertices()], dtype=float).reshape(-1, 2)
            if not np.isfinite(cv).all():
                yield cv, False, filled  # the caller names it as non-finite
                continue
            if len(cv) and np.ptp(cv, axis=0).max() > max_span:
                yield None, False, filled
                continue
            pts = np.array([(v.x, v.y) for v in sub.flattening(sagitta, segments=_MIN_SEGMENTS)], dtype=float)
            if len(pts) < 2:
                continue
            closed = bool(np.allclose(pts[0], pts[-1], rtol=0.0, atol=sagitta * 1e-3)) and len(pts) > 3
            if closed:
                pts = pts[:-1]
            elif filled:
                closed = len(pts) >= 3  # a fill boundary is closed by definition
            yield pts, closed, filled

