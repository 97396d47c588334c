"""Plan reconstruction: strokes per role -> :class:`~mapkit.scene.Scene`.

1. Walls (:mod:`mapkit.importers.dxf.walls`): solids from double lines,
   outlines, fills and columns; single lines thickened. Jamb ticks across
   single-line walls (:mod:`mapkit.importers.dxf.jamb_ticks`) are marks,
   not walls; two with no door drawing at them mark a doorway. The X
   across a lift's or a shaft's box is a mark, not walls
   (:mod:`mapkit.importers.dxf.cross_marks`).
   A single wall line that seals part of a room's outline off with no door
   is not a wall (:mod:`mapkit.importers.dxf.room_outlines`).
2. Openings (:mod:`mapkit.importers.dxf.openings`): each door or window
   drawing claims the wall gap it sits in; free-standing glass becomes an
   obstacle. A door swing over a wall left unbroken under it opens the
   wall where its leaf closes (:mod:`mapkit.importers.dxf.closed_leaf`).
3. Free space: the interior (what closed outlines enclose once door and
   window gaps are shut; for open plans a floor layer's extent, else the
   footprint closed from the walls, :mod:`.closure`) minus walls and
   obstacles, shrunk by the robot radius. A plan that none of these closes
   is refused. Stairs drawn on the wall layer are runs of treads, not
   walls (:mod:`.stairs`): their extent is no floor, and a stair well's
   space that only the stair leads to is not this storey's.
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
from mapkit.importers.dxf.closed_leaf import closed_leaf_opening, walled_swing_doorway
from mapkit.importers.dxf.closure import closed_footprint
from mapkit.importers.dxf.cross_marks import split_cross_marks
from mapkit.importers.dxf.doorway_gaps import wall_doorway_gaps
from mapkit.importers.dxf.enclosure import end_bridges, passable
from mapkit.importers.dxf.jamb_ticks import split_jamb_ticks, tick_doorways
from mapkit.importers.dxf.layer_roles import is_zone_layer
from mapkit.importers.dxf.pocket_doors import pocket_opening
from mapkit.importers.dxf.openings import (cut_opening, door_openings, door_strokes, drawing_items, find_opening, passage_opening,
                                          glass_footprint, opening_width)
from mapkit.importers.dxf.reachable import describe_left_out, entered_parts
from mapkit.importers.dxf.room_layers import door_line_opening, entered_spaces, room_faces
from mapkit.importers.dxf.room_outlines import lines_splitting_rooms, room_outlines
from mapkit.importers.dxf.stairs import (describe_runs, describe_stair_reached, find_stair_runs, stair_reached_parts,
                                         stair_wells, tread_lines, without_stairs, without_treads)
from mapkit.importers.dxf.strokes import PlanDrawing, Stroke
from mapkit.importers.dxf.units import rescale_hint
from mapkit.importers.dxf.walls import build_walls
from mapkit.scene import Opening, Scene
from mapkit.shapes import polygon_parts
from mapkit.tolerances import (DOUBLE_DOOR_SQUARENESS, FLOOR_SURROUNDED_SHARE, MERGE, MIN_FREE_AREA, OPEN_PLAN_FRACTION,
                               OUTLINE_MAX_GAP, SMALL_PLAN_M, SNAP_GAP, ZERO, ZONE_WALLS_DRAWN_SHARE)


def reconstruct_scene(drawing: PlanDrawing, options: BuildOptions, info: dict | None = None) -> Scene:
    """Build the scene of a plan; ``info`` (units, layers, warnings) is completed and stored in it."""
    info = dict(info or {})
    warnings = info.setdefault("warnings", [])
    warn = partial(warn_decision, warnings)

    # Stairs drawn on the wall layer are no walls (:mod:`.stairs`); jamb
    # ticks across single-line walls are marks, not walls (:mod:`.jamb_ticks`).
    stair_runs = find_stair_runs(drawing.role("walls"))
    wall_strokes, ticks = split_jamb_ticks(without_treads(drawing.role("walls"), stair_runs))
    wall_strokes, crosses = split_cross_marks(wall_strokes)  # the X of a lift or shaft is no wall
    if crosses:
        warn(f"{len(crosses)} stroke(s) crossing boxes corner to corner (an X marking a lift or shaft) are marks, "
             "not walls")
    wall_result = build_walls(wall_strokes, options.max_wall_thickness)
    walls = wall_result.walls
    if walls.is_empty:
        _refuse_no_walls(info, options)

    door_items = _door_items(drawing, warn)
    walls, filled_rooms = _with_zone_walls(drawing, walls, options, info, door_items)

    walls, openings, obstacles, door_gaps = _openings(drawing, walls, options, warn, door_items)
    if ticks:
        walls = _tick_doorways(ticks, drawing, walls, openings, door_gaps, options, warn)
    walls = _without_lines_splitting_rooms(drawing, walls, wall_result.single_lines, warn)
    bridges = end_bridges(walls, options.max_wall_thickness)
    interior, interior_source = _interior(walls, door_gaps, obstacles, drawing.role("floor"), bridges,
                                          room_faces(drawing.role("rooms"), drawing.role("doors")))
    _tell_closed_outline(interior_source, drawing, warn)

    free = _free_space(interior, walls, obstacles, options.robot_radius)
    free = _without_shut_in(free, filled_rooms, interior_source, drawing, door_gaps, door_items, options, warn)
    if stair_runs:
        free = _without_stairs(free, stair_runs, [walls, obstacles, *door_gaps, *bridges],
                               door_gaps + _doorways(bridges, interior, obstacles) + door_items, options, warn, info)
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
    if stair_runs:
        ignored["stairs (treads)"] = tread_lines(drawing.role("walls"), stair_runs)
    scene = Scene(
        walls=walls,
        openings=openings,
        free_space=free,
        wall_height=options.wall_height,
        obstacles=obstacles,
        ignored=ignored,
        info=info,
    )
    _refuse_if_empty(scene, interior_source, options, drawing.role("walls"))
    return scene


def _tell_closed_outline(interior_source: str, drawing: PlanDrawing, warn) -> None:
    """Warn when the building's outline was closed from its outer walls (:func:`_interior`)."""
    if interior_source == "closed from the walls":
        warn(f"no closed outline encloses the plan and no floor layer outlines an area; the building's outline is "
             f"closed from its outer walls across gaps up to {OUTLINE_MAX_GAP:g} m")
    elif interior_source == "rooms closed from the walls":
        warn(f"the floor layer(s) {', '.join(sorted({repr(s.layer) for s in drawing.role('floor')}))} outline rooms, "
             f"not the floor: the corridors and halls between them are inside the building's outline, closed from "
             f"its outer walls across gaps up to {OUTLINE_MAX_GAP:g} m")


def _with_zone_walls(drawing: PlanDrawing, walls: MultiPolygon, options: BuildOptions, info: dict, door_items: list):
    """The walls with those room fills (zone layers) leave implicit, and the
    room fills when the walls are drawn beside them (empty otherwise): see
    ``ZONE_WALLS_DRAWN_SHARE``. ``door_items``: the door drawings."""
    zones = _floor_extent([st for st in drawing.role("floor") if is_zone_layer(st.layer)])
    filled_rooms = Polygon()  # the room fills of a plan whose walls are drawn
    if not zones.is_empty:
        between = _between_zones(walls, zones, options.max_wall_thickness)
        if not between.is_empty and between.intersection(walls).area >= ZONE_WALLS_DRAWN_SHARE * between.area:
            # The walls are drawn (the room fills stop at their faces): the
            # strips off them are doorways and openings the walls leave open.
            between = Polygon()
            filled_rooms = zones
        if not between.is_empty:
            # Room fills stop short of the doorways too: where a door sits in
            # a gap of the walls as drawn, the strip is its gap, not a wall.
            gaps = [g for _, g in door_openings(door_items, walls, options.max_wall_thickness) if g is not None]
            if gaps:
                between = between.difference(unary_union(gaps).buffer(SNAP_GAP, join_style="mitre"))
        if not between.is_empty:
            walls = MultiPolygon(polygon_parts(unary_union([walls, between])))
            info["zone_walls_m2"] = round(between.area, 3)
    return walls, filled_rooms


def _refuse_if_empty(scene: Scene, interior_source: str, options: BuildOptions, wall_strokes: list) -> None:
    """Raise :class:`NoFreeSpaceError` (with ``scene``, for previews) when
    the walls enclose no building or leave no free space, naming the fix
    (for a plan too small, the scale its ``wall_strokes``' doorway gaps say)."""
    info, walls, free = scene.info, scene.walls, scene.free_space
    x0, y0, x1, y1 = walls.bounds
    small = max(x1 - x0, y1 - y0) < SMALL_PLAN_M
    if interior_source == "open" and not small:  # (a plan of a room's size: its scale is what is wrong, below)
        raise NoFreeSpaceError(
            f"the walls enclose no building: no closed outline, no floor layer outlining an area, and the outer walls "
            f"stay open across a gap wider than {OUTLINE_MAX_GAP:g} m; outline the building on a layer of its own and "
            f"name it with --floor, or choose the wall layers with --walls (check them with 'mapkit preview')",
            scene,
        )
    if free.is_empty:
        layers = ", ".join(f"'{n}'" for n in info.get("layers", {}).get("walls", [])) or "none"
        hint = ("; " + rescale_hint(x1 - x0, y1 - y0, info.get("units", "m"), info.get("insunits"), options.units,
                                   options.scale, wall_doorway_gaps(wall_strokes)) if small else "")
        raise NoFreeSpaceError(
            f"no free space left inside the walls (layers {layers}) after keeping {options.robot_radius:g} m "
            f"from them; check them with 'mapkit preview', choose wall layers with --walls or lower --robot-radius"
            + hint,
            scene,
        )


def _refuse_no_walls(info: dict, options: BuildOptions):
    """Raise the NoWallsError of a plan whose wall layers form no walls."""
    layers = ", ".join(f"'{n}'" for n in info.get("layers", {}).get("walls", [])) or "none"
    if options.walls:  # the user named them: say what is wrong with them, not to name them
        hint = ("they hold no lines or outlines that form walls (text, points and blocks of other things "
                "do not); check the choice with 'mapkit layers PLAN' and 'mapkit preview PLAN'")
    else:
        hint = "name the wall layers with --walls (see 'mapkit layers PLAN')"
    raise NoWallsError(f"no recognisable walls on the wall layers ({layers}); {hint}")


def _without_lines_splitting_rooms(drawing: PlanDrawing, walls: MultiPolygon, single_lines, warn) -> MultiPolygon:
    """The walls less the single wall lines that seal part of a room's
    outline off with no door (:mod:`.room_outlines`), with a warning."""
    rooms = room_outlines([st for st in drawing.role("floor") if is_zone_layer(st.layer)])
    not_walls = lines_splitting_rooms(rooms, walls, single_lines)
    if not_walls.is_empty:
        return walls
    warn(f"{len(polygon_parts(not_walls))} single wall line(s) across a room's outline, sealing part of the "
         "room off with no door, are taken for overhead or setting-out lines, not walls")
    return MultiPolygon(polygon_parts(walls.difference(not_walls)))


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
    pockets = []
    for item, gap in door_openings(door_items, barriers, options.max_wall_thickness):
        walled = walled_swing_doorway(item, gap, walls, options.max_wall_thickness) if gap is not None else None
        if walled is not None:  # the gap found beside a swing is not where its leaf closes: a wall is
            gap = walled
            cuts.append(walled)
        if gap is None:
            gap = pocket_opening(item, walls, options.max_wall_thickness)
            if gap is not None and not _claimed(gap, door_gaps + window_gaps):
                pockets.append(gap)
                door_gaps.append(gap)
                openings.append(Opening(gap, "door", 0.0, options.door_height))
                continue
            cut = cut_opening(item, walls, options.max_wall_thickness)
            if cut is None:  # a swing over a wall left unbroken under it: opened where its leaf closes
                cut = closed_leaf_opening(item, walls, options.max_wall_thickness)
            # A door drawn as one line (no leaf, no swing) is a door where it meets walls at both ends:
            # across a passage between two walls' faces, a shop front, a lane's end.
            gap = cut if cut is not None else door_line_opening(item, walls)
            if gap is None:  # a door closing a passage between the faces of two walls (or glass) across it
                gap = passage_opening(item, barriers)
            if gap is None or _claimed(gap, door_gaps + window_gaps):
                lost.append(item.centroid)
                continue
            if cut is not None:
                cuts.append(cut)
        if _claimed(gap, door_gaps + window_gaps):
            continue
        door_gaps.append(gap)
        openings.append(Opening(gap, "door", 0.0, options.door_height))
    if pockets:
        warn(f"{len(pockets)} pocket door(s) (a leaf drawn inside the wall): their doorways are the gaps beside them")
    if cuts:
        walls = MultiPolygon(polygon_parts(walls.difference(unary_union(cuts))))
        warn(f"{len(cuts)} door drawing(s) over an unbroken wall: their openings cut through it")
        _join_double_doors(cuts, openings, door_gaps)
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


def _tick_doorways(ticks, drawing: PlanDrawing, walls: MultiPolygon, openings: list[Opening],
                   door_gaps: list[Polygon], options: BuildOptions, warn) -> MultiPolygon:
    """The walls with the doorways that jamb ticks mark and no door drawing
    claims (:func:`.jamb_ticks.tick_doorways`) cut through them; each
    doorway is added to ``openings`` (a door's gap, sill 0) and
    ``door_gaps``."""
    gaps = [g for g in tick_doorways(ticks, drawing_items(drawing.role("doors")), walls)
            if not _claimed(g, door_gaps + [o.footprint for o in openings])]
    if not gaps:
        return walls
    for gap in gaps:
        door_gaps.append(gap)
        openings.append(Opening(gap, "door", 0.0, options.door_height))
    warn(f"{len(gaps)} doorway(s) marked by jamb ticks across a wall line, without a door drawing: opened")
    return MultiPolygon(polygon_parts(walls.difference(unary_union(gaps))))


def _join_double_doors(cuts: list[Polygon], openings: list[Opening], door_gaps: list[Polygon]) -> None:
    """Make the two leaves of a double door drawn over an unbroken wall one
    opening: cut openings that meet end to end in one wall (their union is a
    rectangle, ``DOUBLE_DOOR_SQUARENESS``) become one, in ``openings`` and
    ``door_gaps`` alike (a leaf is drawn and cut on its own; the doorway is
    one)."""
    cut_ids = {id(c) for c in cuts}
    leaves = [o for o in openings if id(o.footprint) in cut_ids]
    joined: set[int] = set()
    for i, a in enumerate(leaves):
        if id(a) in joined:
            continue
        for b in leaves[i + 1:]:
            if id(b) in joined or a.footprint.distance(b.footprint) > MERGE:
                continue
            both = unary_union([a.footprint, b.footprint])
            if not isinstance(both, Polygon) or both.area < DOUBLE_DOOR_SQUARENESS * both.minimum_rotated_rectangle.area:
                continue
            k = next(n for n, o in enumerate(openings) if o is a)
            openings[k] = a = Opening(both, a.kind, a.sill, a.head)
            openings.remove(b)
            door_gaps[:] = [g for g in door_gaps if g is not b.footprint]
            door_gaps.append(both)
            joined.add(id(b))


def _without_stairs(free: MultiPolygon, runs: list, barriers: list, entries: list, options: BuildOptions, warn,
                    info: dict) -> MultiPolygon:
    """The free space less the stair ``runs``' extents, and less the
    spaces in a stair well that only the stair leads to from this storey
    (:mod:`.stairs`; ``barriers``: walls, obstacles, door gaps and
    doorways; ``entries``: door gaps, doorways and door drawings), warned;
    ``info`` counts the runs (``stair_runs``) and the area left out
    (``stair_left_out_m2``)."""
    warn(describe_runs(runs))
    info["stair_runs"] = len(runs)
    free = without_stairs(free, runs, options.robot_radius)
    free, left_out = stair_reached_parts(free, stair_wells(barriers, runs), entries, options.robot_radius)
    if left_out:
        warn(describe_stair_reached(left_out))
        info["stair_left_out_m2"] = round(sum(p.area for p in left_out), 3)
    return free


def _without_shut_in(free: MultiPolygon, filled_rooms, interior_source: str, drawing: PlanDrawing,
                     door_gaps: list[Polygon], door_items: list, options: BuildOptions, warn) -> MultiPolygon:
    """``free`` (metres) without the walled spaces the robot never enters, warned:

    - with room fills beside drawn walls (``filled_rooms``): those no fill
      covers and no door opens (shafts, chases);
    - with a floor layer: those shut in by walls or glass that none of the
      plan's doors (``door_gaps``) opens. A floor layer says where the
      floor is, not where the rooms are (a light box between two glass
      panes);
    - with room polygons (zone layers), which say where rooms are: those
      no door opens and no door drawing left unused (``door_items`` that no
      door gap holds) reaches from outside the other spaces: a shaft, a
      column's hollow core, a store whose door is not drawn. A space such a
      drawing reaches (within ``robot_radius`` and ``max_wall_thickness``:
      a door line along the wall beside it, a swing drawn in the room off
      its wall) is a room whose door was missed: kept, for the self-check
      (:mod:`.self_check`) to refuse. A drawing lying mostly in another
      space (a toilet stall's door, its partitions not drawn as walls)
      opens that space, not this one.
    """
    if not filled_rooms.is_empty:
        free, shafts = _without_shafts(free, filled_rooms, door_gaps, options.robot_radius)
        if shafts:
            warn(f"{len(shafts)} walled space(s) with no room fill and no door (shafts, chases) are not free space: "
                 f"{sum(p.area for p in shafts):.1f} m2")
        return free
    if interior_source not in ("floor layer", "rooms closed from the walls") or not door_gaps:
        return free
    zones = any(is_zone_layer(s.layer) for s in drawing.role("floor"))
    gaps = unary_union(door_gaps)
    unused = [d for d in door_items if zones and d.distance(gaps) > SNAP_GAP]  # door drawings no gap holds
    parts = list(free.geoms)
    largest = max(range(len(parts)), key=lambda k: parts[k].area, default=-1)
    reach = options.robot_radius + options.max_wall_thickness

    def drawn_at(part) -> bool:  # an unused door drawing by the part, no more of it in other spaces than not
        return any(2.0 * (d.intersection(free).length - d.intersection(part).length) <= d.length
                   for d in unused if part.distance(d) <= reach)

    keep, shut_in = [], []
    for k, part in enumerate(parts):
        entered = k == largest or part.distance(gaps) <= options.robot_radius + SNAP_GAP or drawn_at(part)
        (keep if entered else shut_in).append(part)
    if shut_in:
        kind = "no door opens and no door is drawn at" if zones else "with no door into them"
        warn(f"{len(shut_in)} space(s) shut in by walls or glass {kind} are not free space: "
             f"{sum(p.area for p in shut_in):.1f} m2")
    return MultiPolygon(keep)


def _without_shafts(free: MultiPolygon, rooms, door_gaps: list[Polygon], robot_radius: float):
    """``free`` without its parts that no room fill covers and no door
    reaches, and those parts.

    A plan whose every room has a fill (a facility-management plan's room
    polygons) says where its rooms are: a walled space outside all of them
    with no door into it is a shaft or a pipe chase, not a place a robot
    reaches."""
    doors = unary_union(door_gaps) if door_gaps else Polygon()
    keep, shafts = [], []
    for part in free.geoms:
        in_room = part.intersection(rooms).area >= MIN_FREE_AREA
        by_door = not doors.is_empty and part.distance(doors) <= robot_radius + SNAP_GAP
        (keep if in_room or by_door else shafts).append(part)
    return MultiPolygon(keep), shafts


def _largest(free: MultiPolygon) -> Polygon:
    """The largest part of ``free`` (an empty polygon when it is empty)."""
    return max(free.geoms, key=lambda p: p.area, default=Polygon())


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
    """Whether most of ``gap`` is already an opening (two drawings in one gap).

    Only the openings whose boxes meet the gap's are intersected with it
    (one vectorised box test): the others meet it in area 0, which never
    passes, so the answer is the same, without an exact intersection per
    opening of the floor for every gap (quadratic on a large floor)."""
    if not taken:
        return False
    x0, y0, x1, y1 = gap.bounds
    b = shapely.bounds(taken)
    near = np.nonzero((b[:, 0] <= x1) & (b[:, 2] >= x0) & (b[:, 1] <= y1) & (b[:, 3] >= y0))[0]
    return any(gap.intersection(taken[i]).area > 0.5 * min(gap.area, taken[i].area) for i in near)


def _interior(walls: MultiPolygon, door_gaps: list[Polygon], obstacles: MultiPolygon, floor: list[Stroke],
              bridges: list[Polygon] | None = None, rooms: Polygon | MultiPolygon | None = None):
    """Region where the building's inside is, and how it was decided.

    Doors, windows, glass and the undrawn openings between facing wall ends
    (``bridges``, :mod:`.enclosure`) shut their gaps, so the rooms are the
    holes of the union of all barriers; door gaps and the bridges with a
    room on both sides then join the interior (the robot passes through
    them; a bridge to the outside stays shut). A floor layer, when there is
    one, says where the inside is (within the outer walls, when they
    enclose the plan). A plan drawn one layer per room gives ``rooms``:
    the faces its room outlines and door lines enclose, and the spaces the
    barriers enclose that a door opens into (a room whose own outline stays
    open); they say where the inside is, as a floor layer does. Plans still
    open after that (the holes cover less than ``OPEN_PLAN_FRACTION`` of the
    walls' convex hull) are closed from their outer walls (:func:`.closure.closed_footprint`),
    as are those whose only floor layers are room polygons (zone layers:
    they say where rooms are, not where the corridors between them end);
    if that encloses too little as well, the source is ``"open"`` and the
    inside empty (the caller refuses the plan).
    """
    bridges = bridges or []
    shut = unary_union([walls, obstacles, *door_gaps, *bridges])
    # Hairline gaps where glass or a door gap meets a wall must not let the inside leak.
    shut = shut.buffer(SNAP_GAP, join_style="mitre").buffer(-SNAP_GAP, join_style="mitre")
    holes = [Polygon(ring) for poly in shapely.get_parts(shut) if isinstance(poly, Polygon) for ring in poly.interiors]
    enclosed = unary_union(holes) if holes else Polygon()
    hull = shut.convex_hull
    floor_area = _floor_extent(floor, shut)
    if rooms is not None and not rooms.is_empty:
        # Rooms whose own outline the walls around them close (:func:`.room_layers.entered_spaces`) too.
        entered = entered_spaces(holes, door_gaps, bridges, rooms)
        inside, source = unary_union([floor_area, rooms, *entered]), "room outlines"
    elif not floor_area.is_empty and enclosed.area >= OPEN_PLAN_FRACTION * hull.area:
        # The walls enclose the building: a floor layer adds the rooms they
        # leave open, but nothing beyond the outer walls (a floor outline of
        # a terrace or of the next wing drawn beside the plan).
        inside, source = unary_union([enclosed, _floor_within_building(floor_area, closed_footprint(shut))]), \
            "floor layer"
    elif not floor_area.is_empty:
        inside, source = unary_union([enclosed, floor_area]), "floor layer"
    elif enclosed.area >= OPEN_PLAN_FRACTION * hull.area:
        inside, source = enclosed, "enclosed"
    else:
        footprint = closed_footprint(shut)
        if footprint.difference(shut).area >= OPEN_PLAN_FRACTION * hull.area:
            inside, source = unary_union([enclosed, footprint]), "closed from the walls"
        else:
            return Polygon(), "open"
    if source == "floor layer" and all(is_zone_layer(s.layer) for s in floor):
        # Room polygons say where rooms are, not where the floor ends: the corridors and halls between
        # them are inside the outer walls, closed as a plan without a floor layer is.
        footprint = closed_footprint(shut)
        if footprint.difference(shut).area >= OPEN_PLAN_FRACTION * hull.area:
            inside, source = unary_union([inside, footprint]), "rooms closed from the walls"
    # The robot walks through doors: their gaps join the rooms they connect.
    # A small closing seals hairline slits where a gap meets a room (they
    # would block the passage once the free space is shrunk); walls are
    # subtracted afterwards, so it cannot add wall material to the inside.
    doorways = [b for b in bridges if passable(b, inside)] if bridges else []
    inside = unary_union([inside, *door_gaps, *doorways])
    inside = inside.buffer(SNAP_GAP, join_style="mitre").buffer(-SNAP_GAP, join_style="mitre")
    return inside, source


def _floor_within_building(floor_area, footprint):
    """What of a floor layer's ``floor_area`` lies in the building whose
    outer walls close into ``footprint`` (:func:`.closure.closed_footprint`,
    metres): all of it inside the footprint, and each piece beyond it that
    the building surrounds, more than ``FLOOR_SURROUNDED_SHARE`` of its rim
    running along the footprint (an atrium or a courtyard, open to the
    outside through gaps wider than ``OUTLINE_MAX_GAP``: a vehicle ramp, an
    entrance hall's glazing not drawn). A floor outline of a terrace or of
    the next wing drawn beside the building meets it along one side at
    most, or not at all: no free space."""
    inner = floor_area.intersection(footprint)
    rim = footprint.buffer(SNAP_GAP, join_style="mitre")
    surrounded = [p for p in polygon_parts(floor_area.difference(footprint))
                  if p.length > 0 and p.exterior.intersection(rim).length > FLOOR_SURROUNDED_SHARE * p.exterior.length]
    return unary_union([inner, *surrounded]) if surrounded else inner


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


def _floor_extent(floor: list[Stroke], barriers=None) -> Polygon | MultiPolygon:
    """What a floor layer covers: its closed outlines and fills, and the faces its lines enclose,
    with the ``barriers`` (walls, glass, doors' gaps; None: none) where they meet them: a tile
    grid or a floor's edge drawn up to a wall or a glass screen and stopped there encloses the
    floor between its lines and that wall (the faces inside the barriers are no floor)."""
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
        faces = list(shapely.get_parts(shapely.polygonize(shapely.get_parts(unary_union(lines)))))
        polys.extend(faces)
        if faces and barriers is not None and not barriers.is_empty:
            polys.extend(_floor_faces_at_barriers(lines, barriers, max(f.area for f in faces)))
    polys = [p for p in polys if isinstance(p, Polygon | MultiPolygon) and p.area > 0]
    if not polys:
        return Polygon()
    return unary_union(polys)


def _floor_faces_at_barriers(lines: list, barriers, largest: float) -> list[Polygon]:
    """The faces a floor's ``lines`` enclose together with the outlines of
    the ``barriers`` they run up to (a tile grid stopped at a wall or a glass
    screen leaves its last row of tiles open there), no larger than the
    ``largest`` face the lines enclose on their own (m2; a tile): a pool or
    a courtyard that the grid's edge and walls happen to enclose is no tile.
    Faces inside the barriers are left out."""
    # Only the barriers' outlines near the floor's lines: a whole building's are costly to node.
    near = shapely.box(*unary_union(lines).bounds).buffer(SNAP_GAP)
    edges = lines + list(shapely.get_parts(barriers.boundary.intersection(near)))
    faces = shapely.get_parts(shapely.polygonize(shapely.get_parts(unary_union(edges))))
    return [f for f in faces if 0 < f.area <= largest and not barriers.contains(f.representative_point())]


def _strokes_geometry(strokes: list[Stroke]):
    """Ignored strokes as one MultiLineString (closed ones as rings), for previews."""
    lines = []
    for s in strokes:
        pts = s.coords if not s.closed else list(s.coords) + [s.coords[0]]
        if len(pts) >= 2:
            lines.append(shapely.LineString(pts))
    return shapely.MultiLineString(lines)
