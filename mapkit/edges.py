"""3D model edges of a plan-based scene: the straight lines a camera sees.

The walls of a :class:`~mapkit.scene.Scene` are a 2.5D solid: seen from
above, the solid at height z is the wall footprint plus every opening
footprint that is *not* open at that height (the lintel above a door, the
parapet below a window). Between two consecutive breakpoint heights (0, each
sill and head, the wall height) that footprint is constant, so the solid is
a stack of prisms, and its edges are:

- horizontal edges at each breakpoint z: the outline of the footprints'
  symmetric difference (below vs above). At z = 0 that is the wall/floor
  junction, at the top the wall/ceiling junction, in between the lintels of
  doors and the sills and heads of windows;
- vertical edges at the real corners (turn > ``CORNER_DEG``) of each band's
  outline, joined across bands. A vertical at an opening's corner is a jamb.

Collinear pieces of an outline are merged first; pieces shorter than
``min_edge_length`` are dropped.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import MultiPolygon

from mapkit.shapes import rings_of
from linemap.lmap import SegmentKind
from mapkit.options import BuildOptions
from mapkit.scene import Opening, Scene
from mapkit.tolerances import COLLINEAR_DEG, CORNER_DEG, FOOTPRINT_CLOSE_GAP, MERGE, ZONE_REACH


def extract_edges(scene: Scene, options: BuildOptions | None = None) -> tuple[np.ndarray, np.ndarray]:
    """All edges of the scene's extruded walls.

    Returns ``segments`` (N, 2, 3) float64 metres and ``kinds`` (N,) uint8
    (:class:`SegmentKind`). Order: horizontal edges by height, then verticals
    (per height zone, zones in the scene's order); deterministic for a given
    scene.

    A scene with ``height_zones`` (rooms of their own ceiling heights) is
    extruded once per zone to that zone's height, and each pass keeps the
    edges nearest its zone: a wall face belongs to the room it faces, so its
    ceiling junction and the tops of its corners sit at that room's ceiling,
    while floor, sill and lintel edges come out the same in every pass.
    """
    options = options or BuildOptions()
    zones = scene.height_zones
    if not zones:
        segs, kinds = _edges_at_height(scene.walls, scene.openings, float(scene.wall_height), options)
    else:
        segs, kinds = [], []
        for k, zone in enumerate(zones):
            # Only the walls near the zone: a cut this far off lies along another zone, which owns it.
            near = zone.area.buffer(ZONE_REACH)
            walls = scene.walls.intersection(near)
            openings = [o for o in scene.openings if o.footprint.intersects(near)]
            s, kk = _edges_at_height(walls, openings, float(zone.height), options)
            if not s:
                continue
            owner = _nearest_zone(np.stack(s), zones)
            segs += [seg for seg, o in zip(s, owner) if o == k]
            kinds += [kind for kind, o in zip(kk, owner) if o == k]
    if not segs:
        return np.zeros((0, 2, 3)), np.zeros(0, dtype=np.uint8)
    return np.stack(segs), np.asarray(kinds, dtype=np.uint8)


def _nearest_zone(segments: np.ndarray, zones) -> np.ndarray:
    """(N,) index of the zone nearest each segment's midpoint seen from above."""
    mid = 0.5 * (segments[:, 0, :2] + segments[:, 1, :2])
    points = shapely.points(mid)
    areas = np.array([z.area for z in zones], dtype=object)
    return np.argmin(shapely.distance(points[:, None], areas[None, :]), axis=1)


def _edges_at_height(walls, openings: list[Opening], height: float, options: BuildOptions) -> tuple[list, list]:
    """Edges of ``walls`` with ``openings`` extruded to ``height``: lists of (2, 3) arrays and kinds."""
    openings = _openings_below(openings, height)
    levels, footprints = _bands(walls, openings, height)
    segs: list[np.ndarray] = []
    kinds: list[int] = []
    doors = shapely.union_all([o.footprint for o in openings if o.kind == "door"] or [MultiPolygon()])

    # Horizontal edges where the footprint changes.
    for k, z in enumerate(levels):
        below = footprints[k - 1] if k > 0 else MultiPolygon()
        above = footprints[k] if k < len(footprints) else MultiPolygon()
        changed = _clean(below.symmetric_difference(above))
        for a, b in _outline_edges(changed, options.min_edge_length):
            segs.append(np.array([[a[0], a[1], z], [b[0], b[1], z]]))
            kinds.append(_horizontal_kind(z, height, a, b, doors))

    # Vertical edges at real corners of each band, joined across bands.
    verticals: dict[tuple[int, int], list[list[float]]] = {}
    for k, fp in enumerate(footprints):
        z0, z1 = levels[k], levels[k + 1]
        # Two rings touching at a vertex both report it: one vertical per point.
        keys = {(round(x / MERGE), round(y / MERGE)) for x, y in _corners(fp)}
        for key in sorted(keys):
            runs = verticals.setdefault(key, [])
            if runs and abs(runs[-1][1] - z0) < MERGE:
                runs[-1][1] = z1  # continues the run of the band below
            else:
                runs.append([z0, z1])
    opening_corners = _opening_corners(openings)
    for key in sorted(verticals):
        x, y = key[0] * MERGE, key[1] * MERGE
        is_jamb = bool(len(opening_corners)) and np.hypot(*(opening_corners - (x, y)).T).min() < FOOTPRINT_CLOSE_GAP * 2
        for z0, z1 in verticals[key]:
            if z1 - z0 >= options.min_edge_length:
                segs.append(np.array([[x, y, z0], [x, y, z1]]))
                kinds.append(SegmentKind.JAMB if is_jamb else SegmentKind.VERTICAL)
    return segs, kinds


def _openings_below(openings: list[Opening], height: float) -> list[Opening]:
    """The openings of walls ``height`` high: heads above it cut to it (an
    opening to the ceiling has no lintel), openings wholly above it dropped."""
    out = []
    for o in openings:
        if o.sill >= height - MERGE:
            continue
        out.append(o if o.head < height - MERGE else Opening(o.footprint, o.kind, o.sill, height))
    return out


def _bands(walls, openings: list[Opening], height: float) -> tuple[list[float], list]:
    """Breakpoint heights and the solid's footprint in each band between them."""
    cuts = {0.0, height}
    for o in openings:
        cuts.update(z for z in (o.sill, o.head) if 0.0 < z < height)
    levels = sorted(cuts)
    footprints = []
    for z0, z1 in zip(levels[:-1], levels[1:]):
        mid = 0.5 * (z0 + z1)
        closed = [o.footprint for o in openings if not (o.sill <= mid <= o.head)]
        fp = shapely.union_all([walls, *closed]) if closed else walls
        footprints.append(_clean(fp))
    return levels, footprints


def _clean(geom):
    """Close hairline gaps and drop slivers, keeping corners square (mitre joins)."""
    if geom.is_empty:
        return MultiPolygon()
    g = geom.buffer(FOOTPRINT_CLOSE_GAP, join_style="mitre").buffer(-2 * FOOTPRINT_CLOSE_GAP, join_style="mitre")
    return g.buffer(FOOTPRINT_CLOSE_GAP, join_style="mitre")


def _simplified_ring(pts: np.ndarray) -> np.ndarray:
    """Drop ring vertices where the outline turns by less than COLLINEAR_DEG."""
    keep = np.ones(len(pts), dtype=bool)
    while True:
        p = pts[keep]
        if len(p) < 3:
            return p
        turn = _turn_angles(p)
        flat = np.abs(turn) < math.radians(COLLINEAR_DEG)
        if not flat.any():
            return p
        # Remove one vertex per pass where runs of flat vertices adjoin, so
        # that a slowly curving outline is not flattened into a chord.
        idx = np.nonzero(keep)[0]
        drop = idx[flat]
        drop = drop[np.r_[True, np.diff(drop) > 1]]
        keep[drop] = False


def _turn_angles(p: np.ndarray) -> np.ndarray:
    """(n,) signed turn angle at each vertex of a closed ring (n, 2), radians."""
    d_in = p - np.roll(p, 1, axis=0)
    d_out = np.roll(p, -1, axis=0) - p
    cross = d_in[:, 0] * d_out[:, 1] - d_in[:, 1] * d_out[:, 0]
    dot = np.einsum("ij,ij->i", d_in, d_out)
    return np.arctan2(cross, dot)


def _outline_edges(geom, min_length: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Straight pieces (a, b) of every ring of ``geom``, collinear runs merged."""
    out = []
    for pts, _ in rings_of(geom):
        p = _simplified_ring(pts)
        if len(p) < 3:
            continue
        q = np.roll(p, -1, axis=0)
        for a, b in zip(p, q):
            if np.hypot(*(b - a)) >= min_length:
                out.append((a, b))
    return out


def _corners(geom) -> list[tuple[float, float]]:
    """Ring vertices of ``geom`` where the outline turns by more than CORNER_DEG."""
    out = []
    for pts, _ in rings_of(geom):
        p = _simplified_ring(pts)
        if len(p) < 3:
            continue
        sharp = np.abs(_turn_angles(p)) > math.radians(CORNER_DEG)
        out += [tuple(v) for v in p[sharp]]
    return out


def _opening_corners(openings: list[Opening]) -> np.ndarray:
    pts = [pts for o in openings for pts, _ in rings_of(o.footprint)]
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def _horizontal_kind(z: float, height: float, a: np.ndarray, b: np.ndarray, doors) -> int:
    if z <= MERGE:
        return SegmentKind.FLOOR
    if z >= height - MERGE:
        return SegmentKind.CEILING
    mid = shapely.points(0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]))
    if not doors.is_empty and shapely.distance(mid, doors) < 2 * FOOTPRINT_CLOSE_GAP:
        return SegmentKind.LINTEL
    return SegmentKind.WINDOW
