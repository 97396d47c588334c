"""Plan reconstruction: strokes per role -> :class:`~mapkit.scene.Scene`.

1. Walls (:mod:`mapkit.importers.dxf.walls`): solids from double lines,
   outlines, fills and columns; single lines thickened.
2. Openings (:mod:`mapkit.importers.dxf.openings`): each door or window
   drawing claims the wall gap it sits in; free-standing glass becomes an
   obstacle.
3. Free space: the interior (what closed outlines enclose once door and
   window gaps are shut; for open plans a floor layer's extent or the walls'
   convex hull) minus walls and obstacles, shrunk by the robot radius.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.ops import unary_union

from mapkit.importers import warn_decision
from mapkit.errors import NoFreeSpaceError, NoWallsError
from mapkit.options import BuildOptions
from mapkit.importers.dxf.enclosure import end_bridges, passable
from mapkit.importers.dxf.layer_roles import is_zone_layer
from mapkit.importers.dxf.openings import cut_opening, door_openings, door_strokes, drawing_items, find_opening, glass_footprint, opening_width
from mapkit.importers.dxf.reachable import describe_left_out, entered_parts
from mapkit.importers.dxf.strokes import PlanDrawing, Stroke
from mapkit.importers.dxf.units import rescale_hint
from mapkit.importers.dxf.walls import build_walls
from mapkit.scene import Opening, Scene
from mapkit.shapes import polygon_parts
from mapkit.tolerances import MIN_FREE_AREA, OPEN_PLAN_FRACTION, SMALL_PLAN_M, SNAP_GAP, ZERO


def reconstruct_scene(drawing: PlanDrawing, options: BuildOptions, info: dict | None = None) -> Scene:
    """Build the scene of a plan; ``info`` (units, layers, warnings) is completed and stored in it."""
    info = dict(info or {})
    warnings = info.setdefault("warnings", [])

    warn = partial(warn_decision, warnings)

    wall_result = build_walls(drawing.role("walls"), options.max_wall_thickness)
    walls = wall_result.walls
    if walls.is_empty:
        layers = ", ".join(f"'{n}'" for n in info.get("layers", {}).get("walls", [])) or "none"
        if options.walls:  # the user named them: say what is wrong with them, not to name them
            hint = ("they hold no lines or outlines that form walls (text, points and blocks of other things "
                    "do not); check the choice with 'mapkit layers PLAN' and 'mapkit preview PLAN'")
        else:
            hint = "name the wall layers with --walls (see 'mapkit layers PLAN')"
        raise NoWallsError(f"no recognisable walls on the wall layers ({layers}); {hint}")

    door_items = _door_items(drawing, warn)
    zones = _floor_extent([st for st in drawing.role("floor") if is_zone_layer(st.layer)])
    if not zones.is_empty:
        between = _between_zones(walls, zones, options.max_wall_thickness)
        if not between.is_empty:
            # Room fills stop short of the doorways too: where a door sits in
            # a gap of the walls as drawn, the strip is its gap, not a wall.
            gaps = [g for _, g in door_openings(door_items, walls, options.max_wall_thickness) if g is not None]
            if gaps:
                between = between.difference(unary_union(gaps).buffer(SNAP_GAP, join_style="mitre"))
        if not between.is_empty:
            walls = MultiPolygon(polygon_parts(unary_union([walls, between])))
            info["zone_walls_m2"] = round(between.area, 3)

    walls, openings, obstacles, door_gaps = _openings(drawing, walls, options, warn, door_items)
    bridges = end_bridges(walls, options.max_wall_thickness)
    interior, interior_source = _interior(walls, door_gaps, obstacles, drawing.role("floor"), bridges)
    if interior_source == "convex hull":
        warn("no closed outline encloses the plan and there is no floor layer; using the walls' convex hull as the interior")

    free = _free_space(interior, walls, obstacles, options.robot_radius)
    if interior_source == "enclosed" and door_gaps:
        free = _entered(free, door_gaps + _doorways(bridges, interior, obstacles) + door_items, options, warn, info)

    info["interior"] = interior_source
    info["counts"] = dict(wall_result.counts) | {
        "doors": sum(o.kind == "door" for o in openings),
        "windows": sum(o.kind == "window" for o in openings),
    }
    info["areas_m2"] = {
        "walls": round(walls.area, 3),
        "free_space": round(free.area, 3),
        "obstacles": round(obstacles.area, 3),
        "interior": round(interior.area, 3),
    }
    ignored = {layer: _strokes_geometry(strokes) for layer, strokes in drawing.ignored.items()}
    scene = Scene(
        walls=walls,
        openings=openings,
        free_space=free,
        wall_height=options.wall_height,
        obstacles=obstacles,
        ignored=ignored,
        info=info,
    )
    if free.is_empty:
        layers = ", ".join(f"'{n}'" for n in info.get("layers", {}).get("walls", [])) or "none"
        x0, y0, x1, y1 = walls.bounds
        small = max(x1 - x0, y1 - y0) < SMALL_PLAN_M
        hint = ("; " + rescale_hint(x1 - x0, y1 - y0, info.get("units", "m"), info.get("insunits"), options.units,
                                   options.scale) if small else "")
        raise NoFreeSpaceError(
            f"no free space left inside the walls (layers {layers}) after keeping {options.robot_radius:g} m "
            f"from them; check them with 'mapkit preview', choose wall layers with --walls or lower --robot-radius"
            + hint,
            scene,
        )
    return scene


def _openings(drawing: PlanDrawing, walls: MultiPolygon, options: BuildOptions, warn, door_items: list | None = None):
    """The walls (with the openings of doors drawn over unbroken walls cut
    through them), openings, obstacles (windows, glass) and door gap
    footprints. ``door_items``: the door drawings (default: the drawing's)."""
    door_items = drawing_items(drawing.role("doors")) if door_items is None else door_items
    openings: list[Opening] = []
    glass_parts = []
    window_gaps = []
    for item in drawing_items(drawing.role("windows")):
        gap = find_opening(item, walls, options.max_wall_thickness)
        if gap is None:
            glass_parts.append(glass_footprint(item))
            continue
        if _claimed(gap, window_gaps):
            continue
        window_gaps.append(gap)
        openings.append(Opening(gap, "window", options.window_sill, options.window_head))
    glass = unary_union(glass_parts) if glass_parts else Polygon()

    # Doors may sit in glass walls (a pavilion) as well as in walls.
    barriers = unary_union([walls, glass]) if not glass.is_empty else walls
    door_gaps = []
    lost = []
    cuts = []
    for item, gap in door_openings(door_items, barriers, options.max_wall_thickness):
        if gap is None:
            gap = cut_opening(item, walls, options.max_wall_thickness)
            if gap is None or _claimed(gap, door_gaps + window_gaps):
                lost.append(item.centroid)
                continue
            cuts.append(gap)
        if _claimed(gap, door_gaps + window_gaps):
            continue
        door_gaps.append(gap)
        openings.append(Opening(gap, "door", 0.0, options.door_height))
    if cuts:
        walls = MultiPolygon(polygon_parts(walls.difference(unary_union(cuts))))
        warn(f"{len(cuts)} door drawing(s) over an unbroken wall: their openings cut through it")
    if lost:
        where = ", ".join(f"({p.x:.1f}, {p.y:.1f})" for p in lost[:5]) + (" ..." if len(lost) > 5 else "")
        warn(f"{len(lost)} door drawing(s) are not in a wall gap and were ignored, at {where} m; check them in 'mapkit preview'")
    narrow = [o for o in openings if opening_width(o.footprint) < 0.5]
    if narrow:
        warn(f"{len(narrow)} opening(s) narrower than 0.5 m; check them in 'mapkit preview'")

    # Glass doors: the door's gap is passable even where glass was drawn across it.
    if door_gaps and not glass.is_empty:
        glass = glass.difference(unary_union(door_gaps))
    obstacles = unary_union([*window_gaps, glass]) if (window_gaps or not glass.is_empty) else Polygon()
    obstacles = MultiPolygon([p for p in shapely.get_parts(obstacles) if isinstance(p, Polygon) and p.area > 0])
    return walls, openings, obstacles, door_gaps


def _free_space(interior, walls, obstacles, robot_radius: float) -> MultiPolygon:
    """Where the robot's centre may be: the interior less walls and
    obstacles, shrunk by ``robot_radius`` (m), slivers under
    ``MIN_FREE_AREA`` dropped."""
    free = interior.difference(walls)
    if not obstacles.is_empty:
        free = free.difference(obstacles)
    # Radii below a nanometre are zero (GEOS empties polygons buffered by denormal distances).
    if robot_radius > ZERO.distance:
        free = free.buffer(-robot_radius)
    return MultiPolygon([p for p in shapely.get_parts(free) if isinstance(p, Polygon) and p.area >= MIN_FREE_AREA])


def _door_items(drawing: PlanDrawing, warn) -> list:
    """The door drawings (:func:`.openings.drawing_items`) of the door
    layers' strokes, less the strokes too long to be part of one (warned)."""
    doors, strays = door_strokes(drawing.role("doors"))
    if strays:
        longest = max(float(np.hypot(*np.ptp(s.coords, axis=0)[:2])) for s in strays)
        warn(f"{len(strays)} stroke(s) on the door layer(s) span more than a door drawing can "
             f"(up to {longest:.0f} m; layers {', '.join(sorted({repr(s.layer) for s in strays}))}): a dimension "
             f"chain or an outline, not doors; left out of the doors")
    return drawing_items(doors)


def _entered(free: MultiPolygon, entries: list, options: BuildOptions, warn, info: dict) -> MultiPolygon:
    """The free space less the spaces the walls enclose that none of
    ``entries`` (door gaps, doorways, door drawings) leads into: shafts,
    light wells, roofs are no rooms (:mod:`.reachable`); warned and counted
    in ``info["left_out_m2"]``. Only for interiors the walls enclose: a
    floor layer or the hull says where the inside is by itself."""
    free, left_out = entered_parts(free, entries, options.robot_radius)
    if left_out:
        warn(describe_left_out(left_out))
        info["left_out_m2"] = round(sum(p.area for p in left_out), 3)
    return free


def _doorways(bridges: list[Polygon], inside, obstacles) -> list[Polygon]:
    """The ``bridges`` (openings between wall ends) that join two rooms and
    hold no window or glass: the robot passes through them."""
    return [b for b in bridges if passable(b, inside) and not _claimed(b, polygon_parts(obstacles))]


def _claimed(gap: Polygon, taken: list[Polygon]) -> bool:
    """Whether most of ``gap`` is already an opening (two drawings in one gap)."""
    return any(gap.intersection(t).area > 0.5 * min(gap.area, t.area) for t in taken)


def _interior(walls: MultiPolygon, door_gaps: list[Polygon], obstacles: MultiPolygon, floor: list[Stroke],
              bridges: list[Polygon] | None = None):
    """Region where the building's inside is, and how it was decided.

    Doors, windows, glass and the undrawn openings between facing wall ends
    (``bridges``, :mod:`.enclosure`) shut their gaps, so the rooms are the
    holes of the union of all barriers; door gaps and the bridges with a
    room on both sides then join the interior (the robot passes through
    them; a bridge to the outside stays shut). A floor layer, when there is
    one, says where the inside is. Plans still open after that (the holes
    cover less than ``OPEN_PLAN_FRACTION`` of the walls' convex hull) take
    the hull.
    """
    bridges = bridges or []
    shut = unary_union([walls, obstacles, *door_gaps, *bridges])
    # Hairline gaps where glass or a door gap meets a wall must not let the inside leak.
    shut = shut.buffer(SNAP_GAP, join_style="mitre").buffer(-SNAP_GAP, join_style="mitre")
    holes = [Polygon(ring) for poly in shapely.get_parts(shut) if isinstance(poly, Polygon) for ring in poly.interiors]
    enclosed = unary_union(holes) if holes else Polygon()
    hull = shut.convex_hull
    floor_area = _floor_extent(floor)
    if not floor_area.is_empty:
        inside, source = unary_union([enclosed, floor_area]), "floor layer"
    elif enclosed.area >= OPEN_PLAN_FRACTION * hull.area:
        inside, source = enclosed, "enclosed"
    else:
        inside, source = hull, "convex hull"
    # The robot walks through doors: their gaps join the rooms they connect.
    # A small closing seals hairline slits where a gap meets a room (they
    # would block the passage once the free space is shrunk); walls are
    # subtracted afterwards, so it cannot add wall material to the inside.
    doorways = [b for b in bridges if passable(b, inside)] if bridges else []
    inside = unary_union([inside, *door_gaps, *doorways])
    inside = inside.buffer(SNAP_GAP, join_style="mitre").buffer(-SNAP_GAP, join_style="mitre")
    return inside, source


def _between_zones(walls, zones, max_wall_thickness: float):
    """Walls a plan drawn as room polygons leaves implicit: the thin strips
    (thinner than ``max_wall_thickness``) between its rooms, and between
    its rooms and the outline the walls enclose (a facade contour)."""
    half = max_wall_thickness / 2.0
    holes = [Polygon(r) for p in polygon_parts(walls) for r in p.interiors]
    envelope = unary_union(holes) if holes else Polygon()
    closed = zones.buffer(half, join_style="mitre").buffer(-half, join_style="mitre")
    candidates = unary_union([envelope.difference(zones), closed.difference(zones)])
    thin = [p for p in polygon_parts(candidates) if p.area > 0 and p.buffer(-half * 0.999).is_empty]
    return unary_union(thin) if thin else Polygon()


def _floor_extent(floor: list[Stroke]) -> Polygon | MultiPolygon:
    """What a floor layer covers: its closed outlines and fills, and the faces its lines enclose."""
    if not floor:
        return Polygon()
    lines = []
    polys = []
    for s in floor:
        if (s.closed or s.filled) and len(s.coords) >= 3:
            polys.append(shapely.make_valid(Polygon(s.coords)))
        elif len(s.coords) >= 2:
            lines.append(shapely.LineString(s.coords))
    if lines:
        noded = unary_union(lines)
        polys.extend(shapely.get_parts(shapely.polygonize(shapely.get_parts(noded))))
    polys = [p for p in polys if isinstance(p, Polygon | MultiPolygon) and p.area > 0]
    if not polys:
        return Polygon()
    return unary_union(polys)


def _strokes_geometry(strokes: list[Stroke]):
    """Ignored strokes as one MultiLineString (closed ones as rings), for previews."""
    lines = []
    for s in strokes:
        pts = s.coords if not s.closed else list(s.coords) + [s.coords[0]]
        if len(pts) >= 2:
            lines.append(shapely.LineString(pts))
    return shapely.MultiLineString(lines)
