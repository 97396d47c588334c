"""Door and window openings: the gap in a wall that a door or window drawing sits in.

A door (leaf + swing arc, often a block) or a window (parallel lines across
the wall) touches the wall at its two jambs. The opening footprint is the
gap between those jambs across the wall's thickness: the convex hull of the
wall ends near the jambs, minus the walls.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import LineString, MultiLineString, Polygon
from shapely.ops import nearest_points, unary_union

from mapkit.importers.dxf.strokes import Stroke
from mapkit.tolerances import (CUT_MIN_REACH, CUT_MIN_WALL_SHARE, DOOR_STROKE_MAX_SPAN, JAMB_REACH, MAX_DOOR_WIDTH, MERGE, MIN_OPENING_WIDTH,
                                THIN_WALL, ZERO)


def drawing_items(strokes: list[Stroke]) -> list[MultiLineString]:
    """The separate doors (or windows) of a layer's strokes.

    Strokes of one block insert form one item; loose strokes closer than
    ``JAMB_REACH`` (the lines of one window, a leaf and its arc) are one item.
    """
    groups: dict[int, list] = {}
    loose = []
    for s in strokes:
        pts = np.asarray(s.coords, dtype=float)
        if s.closed:
            pts = np.vstack([pts, pts[:1]])
        if len(pts) < 2:
            continue
        line = LineString(pts)
        if s.group is not None:
            groups.setdefault(s.group, []).append(line)
        else:
            loose.append(line)
    items = [unary_union(lines) for lines in groups.values()]
    if loose:
        blobs = shapely.get_parts(unary_union([g.buffer(JAMB_REACH / 2) for g in loose]))
        tree = shapely.STRtree(loose)
        for blob in blobs:
            items.append(unary_union([loose[i] for i in tree.query(blob, predicate="contains")]))
    return [_lines(item) for item in items if not item.is_empty]


def door_strokes(strokes: list[Stroke]) -> tuple[list[Stroke], list[Stroke]]:
    """``(doors, strays)``: the strokes of door layers that can be part of a
    door drawing, and those spanning more than ``DOOR_STROKE_MAX_SPAN`` (a
    dimension chain or an outline on a door layer), which are not."""
    doors, strays = [], []
    for s in strokes:
        pts = np.asarray(s.coords, dtype=float)
        span = float(np.hypot(*(pts.max(axis=0) - pts.min(axis=0))[:2])) if len(pts) else 0.0
        (strays if span > DOOR_STROKE_MAX_SPAN else doors).append(s)
    return doors, strays


def find_opening(item: MultiLineString, barriers, max_wall_thickness: float) -> Polygon | None:
    """Footprint of the wall gap the drawing ``item`` sits in, or None if it is in no gap.

    ``barriers``: wall solids (and glass, for doors in glass walls). The gap
    runs between the two jambs the drawing touches; across, it spans the
    wall's thickness measured at the jambs (a jamb that is the side of a
    perpendicular wall, not a wall end, gives no thickness).
    """
    near = barriers.intersection(item.buffer(JAMB_REACH))
    jambs = [g for g in shapely.get_parts(near) if g.area > 0]
    if len(jambs) < 2:
        return None
    # The two jambs farthest apart span the gap (a door near a corner may
    # touch a third wall piece; the gap is still between the outer two).
    centres = np.array([[p.x, p.y] for p in (j.representative_point() for j in jambs)])
    d = np.linalg.norm(centres[:, None] - centres[None], axis=-1)
    i, k = np.unravel_index(np.argmax(d), d.shape)
    # The gap runs between the jambs' facing points (a swing arc can graze a
    # long stretch of wall, so the pieces' centres may be far from the jamb).
    pa, pb = nearest_points(jambs[i], jambs[k])
    a, b = np.array([pa.x, pa.y]), np.array([pb.x, pb.y])
    width = float(np.hypot(*(b - a)))
    if width < MIN_OPENING_WIDTH:
        return None
    axis = _wall_direction((b - a) / width, barriers, (jambs[i], jambs[k]))
    width = float((b - a) @ axis)
    if width < 0:
        axis, width = -axis, -width
    b = a + axis * width  # on the axis through a: the zone below is a rectangle
    normal = np.array([-axis[1], axis[0]])
    # Probe the wall thickness just inside each jamb face.
    inset = 5 * MERGE
    probes = (a - axis * inset, b + axis * inset)
    bands = [_thickness_band(p, normal, a, barriers, max_wall_thickness) for p in probes]
    bands = [band for band in bands if band is not None]
    if bands:
        lo, hi = min(band[0] for band in bands), max(band[1] for band in bands)
    else:
        # Jambs are the sides of walls running across (a glass screen between
        # two walls): that is no wall gap.
        return None
    reach = JAMB_REACH
    zone = Polygon(
        [
            a - axis * reach + normal * lo,
            b + axis * reach + normal * lo,
            b + axis * reach + normal * hi,
            a - axis * reach + normal * hi,
        ]
    )
    gap = zone.difference(barriers)
    # The zone is square to the jamb axis, which may be a hair off the wall's
    # direction: shave the hairline slivers that leaves along the wall faces.
    gap = shapely.make_valid(gap).buffer(-2 * MERGE, join_style="mitre").buffer(2 * MERGE, join_style="mitre")
    pieces = [g for g in shapely.get_parts(gap) if isinstance(g, Polygon) and g.area > 0]
    if not pieces:
        return None
    touching = item.buffer(JAMB_REACH)
    best = max(pieces, key=lambda g: g.intersection(touching).area)
    if best.intersection(touching).area <= 0:
        return None
    return best


def door_openings(items: list[MultiLineString], barriers, max_wall_thickness: float) -> list[tuple[MultiLineString, Polygon | None]]:
    """Each door drawing with the wall gap it sits in (None if none).

    A drawing between two jambs is found by :func:`find_opening`. The
    leaves of a double door are two drawings, each at one jamb: drawings
    that found no gap alone and touch each other are tried together. A door
    at the end of a wall, with no wall on its latch side, gets the gap its
    drawing spans from that end (:func:`opening_at_wall_end`)."""
    found = [(item, find_opening(item, barriers, max_wall_thickness)) for item in items]
    alone = [k for k, (_, gap) in enumerate(found) if gap is None]
    merged: set[int] = set()
    for i in alone:
        if i in merged:
            continue
        for j in alone:
            if j <= i or j in merged or found[i][0].distance(found[j][0]) > JAMB_REACH:
                continue
            both = _lines(unary_union([found[i][0], found[j][0]]))
            gap = find_opening(both, barriers, max_wall_thickness)
            if gap is not None:
                found[i] = (both, gap)
                merged.add(j)
                break
    out = []
    for k, (item, gap) in enumerate(found):
        if k in merged:
            continue
        if gap is None:
            gap = opening_at_wall_end(item, barriers, max_wall_thickness)
        out.append((item, gap))
    return out


def opening_at_wall_end(item: MultiLineString, barriers, max_wall_thickness: float) -> Polygon | None:
    """The gap a door drawing spans from the end of a wall it meets, when no
    wall stands on its other side: from the wall's end face, along the wall,
    as far as the drawing reaches (at least ``MIN_OPENING_WIDTH``), as wide
    as the wall is thick, stopped by any wall in the way. None when the
    drawing meets no wall end."""
    from mapkit.importers.dxf.enclosure import wall_ends

    x0, y0, x1, y1 = item.bounds
    pad = JAMB_REACH + max_wall_thickness
    local = _clipped(barriers, (x0 - pad, y0 - pad, x1 + pad, y1 + pad))
    a, b, out = wall_ends(local, max_wall_thickness)
    if len(a) == 0:
        return None
    coords = np.concatenate([np.asarray(g.coords)[:, :2] for g in item.geoms])
    best = None
    for k in range(len(a)):
        face = LineString([a[k], b[k]])
        if face.distance(item) > JAMB_REACH:
            continue
        c = (a[k] + b[k]) / 2.0
        reach = float(((coords - c) @ out[k]).max())
        if reach < MIN_OPENING_WIDTH:
            continue
        zone = Polygon([a[k], b[k], b[k] + out[k] * reach, a[k] + out[k] * reach])
        gap = zone.difference(barriers)
        piece = max((g for g in shapely.get_parts(gap) if isinstance(g, Polygon)), key=lambda g: g.area, default=None)
        if piece is None or piece.area <= 0 or (best is not None and piece.area <= best.area):
            continue
        best = piece
    return best


def _clipped(geom, box: tuple[float, float, float, float]):
    """``geom`` cut to the rectangle ``box`` (x0, y0, x1, y1).

    GEOS's fast rectangle clip refuses some valid inputs (walls drawn as
    single lines on one layer per room: a ring of the clip's result
    collapses to 3 points, IllegalArgumentException); the general
    intersection handles them, more slowly, so it is the fallback only."""
    try:
        return shapely.clip_by_rect(geom, *box)
    except shapely.errors.GEOSException:
        cut = geom.intersection(shapely.box(*box))
        return shapely.MultiPolygon([g for g in shapely.get_parts(cut) if isinstance(g, Polygon)])


def _wall_direction(axis: np.ndarray, barriers, jambs) -> np.ndarray:
    """The direction of the wall faces at the jambs closest to ``axis`` (within 15 degrees).

    Points inside the two jambs give the gap's direction only roughly; the
    wall's own edges give it exactly, so the footprint is square to the wall.
    """
    near = shapely.union_all([j.buffer(MERGE) for j in jambs])
    # Clip first: the boundary of a whole building's walls is costly to build per opening.
    # The clip box reaches past ``near`` so that its own cut edges fall outside it.
    x0, y0, x1, y1 = near.bounds
    pad = 10 * MERGE
    edges = _clipped(barriers, (x0 - pad, y0 - pad, x1 + pad, y1 + pad)).boundary.intersection(near)
    return longest_edge_along(edges, axis, 15.0)


def longest_edge_along(edges, axis: np.ndarray, max_angle_deg: float) -> np.ndarray:
    """The unit direction of the longest straight piece of ``edges`` (lines)
    within ``max_angle_deg`` of ``axis`` (unit 2-vector), turned to point
    along it; ``axis`` when no piece longer than ``MERGE`` is that close."""
    best, best_len = axis, 0.0
    cos_max = np.cos(np.radians(max_angle_deg))
    for part in shapely.get_parts(edges):
        coords = np.asarray(getattr(part, "coords", []))
        for p, q in zip(coords[:-1], coords[1:]):
            d = np.asarray(q[:2]) - np.asarray(p[:2])
            length = float(np.hypot(*d))
            if length <= MERGE:
                continue
            d = d / length
            c = float(d @ axis)
            if abs(c) >= cos_max and length > best_len:
                best, best_len = (d if c > 0 else -d), length
    return best


def _thickness_band(probe, normal, origin, barriers, max_wall_thickness: float) -> tuple[float, float] | None:
    """Extent ``(lo, hi)`` along ``normal`` (from ``origin``) of the wall through ``probe``.

    None when the wall there is thicker than ``max_wall_thickness`` (the probe
    sits in a wall running along the normal, not at a wall end).
    """
    reach = max_wall_thickness
    ray = LineString([probe - normal * reach, probe + normal * reach])
    hit = ray.intersection(barriers)
    point = shapely.Point(probe)
    for seg in shapely.get_parts(hit):
        if isinstance(seg, LineString) and seg.distance(point) < ZERO.distance:
            ts = sorted(float((np.asarray(c[:2]) - origin) @ normal) for c in (seg.coords[0], seg.coords[-1]))
            if ts[1] - ts[0] >= 2 * reach - ZERO.derived_length or ts[1] - ts[0] > max_wall_thickness:
                return None
            return ts[0], ts[1]
    return None


def cut_opening(item: MultiLineString, walls, max_wall_thickness: float) -> Polygon | None:
    """Footprint of the opening a door drawn over an unbroken wall stands
    for, or None when the drawing is not over a wall.

    People draw doors over the wall line without breaking it (a swing on a
    single-line wall, a rectangle across a double-line one). The wall piece
    under the drawing gives the wall's direction (its rotated bounding
    box's long side) and thickness (its extent across); the drawing's
    extent along the wall is the door's width, between ``MIN_OPENING_WIDTH``
    and ``MAX_DOOR_WIDTH``. The drawing must reach about half way into the wall's
    thickness, and the footprint, that rectangle, lie mostly
    (``CUT_MIN_WALL_SHARE``) in wall: else the drawing is beside the wall,
    not over it."""
    under = shapely.make_valid(walls.intersection(item.buffer(JAMB_REACH)))
    parts = [g for g in shapely.get_parts(under) if isinstance(g, Polygon) and g.area > 0]
    if not parts:
        return None
    piece = max(parts, key=lambda g: g.area)
    rect = np.asarray(piece.minimum_rotated_rectangle.exterior.coords)[:4]
    sides = np.diff(np.vstack([rect, rect[:1]]), axis=0)
    long = sides[np.argmax(np.linalg.norm(sides, axis=1))]
    if not np.linalg.norm(long) > 0:
        return None
    axis = long / np.linalg.norm(long)
    normal = np.array([-axis[1], axis[0]])
    pts = np.concatenate([np.asarray(g.coords)[:, :2] for g in shapely.get_parts(item)])
    t, across = pts @ axis, pts @ normal
    t0, t1 = float(t.min()), float(t.max())
    if not MIN_OPENING_WIDTH <= t1 - t0 <= MAX_DOOR_WIDTH:
        return None
    wall_across = np.asarray(piece.exterior.coords)[:, :2] @ normal
    s0, s1 = float(wall_across.min()), float(wall_across.max())
    # Over the wall, not beside it: the drawing reaches about half way
    # (``CUT_MIN_REACH``) across the wall under it (a swing's hinge on a
    # single-line wall, a rectangle across a double-line one; a door drawn
    # against a wall's face only touches it).
    reach = min(s1, float(across.max())) - max(s0, float(across.min()))
    if s1 - s0 > max_wall_thickness or reach < CUT_MIN_REACH * (s1 - s0):
        return None
    footprint = Polygon([axis * t0 + normal * s0, axis * t1 + normal * s0, axis * t1 + normal * s1,
                         axis * t0 + normal * s1])
    if walls.intersection(footprint).area < CUT_MIN_WALL_SHARE * footprint.area:
        return None
    return footprint


def passage_opening(item: MultiLineString, barriers) -> Polygon | None:
    """The opening of a door that closes a passage between the faces of two
    barriers running across it (a door across a corridor between two
    walls' faces, a double door between a glass screen's end and a wall),
    where :func:`find_opening` finds no wall gap: the line between the two
    barrier pieces farthest apart that the drawing ``item`` touches (its
    jambs), ``THIN_WALL`` deep. None when it touches fewer than two, the
    line is shorter than ``MIN_OPENING_WIDTH``, or runs mostly in a barrier
    (a door drawn against a wall's face)."""
    near = barriers.intersection(item.buffer(JAMB_REACH))
    jambs = [g for g in shapely.get_parts(near) if g.area > 0]
    if len(jambs) == 1:
        line = _across_to_barrier(item, jambs[0], barriers)
        if line is None:
            return None
    elif len(jambs) >= 2:
        centres = np.array([[p.x, p.y] for p in (j.representative_point() for j in jambs)])
        d = np.linalg.norm(centres[:, None] - centres[None], axis=-1)
        i, k = np.unravel_index(np.argmax(d), d.shape)
        line = LineString(nearest_points(jambs[i], jambs[k]))
    else:
        return None
    if line.length < MIN_OPENING_WIDTH or barriers.intersection(line).length > 0.5 * line.length:
        return None
    return line.buffer(THIN_WALL / 2.0, cap_style="flat")


def _across_to_barrier(item: MultiLineString, jamb, barriers) -> LineString | None:
    """For a door drawing that touches one barrier (``jamb``) and stops
    short of the other side of its passage: the line from that jamb along
    the drawing's longer side (its rotated bounding box's) to the first
    barrier met, reached at least half way by the drawing; None otherwise."""
    box = item.minimum_rotated_rectangle  # a line's is the line
    rect = np.asarray(box.exterior.coords if box.geom_type == "Polygon" else box.coords)[:, :2]
    sides = np.diff(rect, axis=0)
    if not len(sides):
        return None
    long = sides[np.argmax(np.linalg.norm(sides, axis=1))]
    if not np.linalg.norm(long) > 0:
        return None
    start, _ = nearest_points(jamb, item)
    a = np.array([start.x, start.y])
    pts = np.concatenate([np.asarray(g.coords)[:, :2] for g in item.geoms])
    axis = long / np.linalg.norm(long)
    reach = (pts - a) @ axis
    if abs(reach.min()) > abs(reach.max()):
        axis, reach = -axis, -reach
    ray = LineString([a + axis * JAMB_REACH, a + axis * 2.0 * float(reach.max())])
    hit = barriers.intersection(ray)
    if hit.is_empty:
        return None
    end, _ = nearest_points(hit, shapely.Point(a))
    b = np.array([end.x, end.y])
    if float(reach.max()) < 0.5 * float(np.hypot(*(b - a))):
        return None
    return LineString([a, b])


def glass_footprint(item: MultiLineString) -> Polygon:
    """Footprint of free-standing glass (no wall gap): the lines thickened to ``THIN_WALL``.

    Square caps let the glass overlap the walls it meets, so it shuts them.
    """
    return item.buffer(THIN_WALL / 2.0, cap_style="square", join_style="mitre")


def opening_width(footprint: Polygon) -> float:
    """Width of a gap footprint: the longer side of its minimum rotated rectangle, metres."""
    rect = np.asarray(footprint.minimum_rotated_rectangle.exterior.coords)[:4]
    sides = np.linalg.norm(np.diff(np.vstack([rect, rect[:1]]), axis=0), axis=1)
    return float(sides.max())


def _lines(geom) -> MultiLineString:
    return MultiLineString([g for g in shapely.get_parts(geom) if isinstance(g, LineString) and not g.is_empty])


__all__ = ["cut_opening", "door_openings", "door_strokes", "drawing_items", "find_opening", "glass_footprint", "passage_opening", "opening_at_wall_end", "opening_width"]
