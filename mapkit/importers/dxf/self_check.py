"""The map checks itself against its drawing before it is written.

The reconstruction (:mod:`.reconstruct`) decides what is wall, door and
free space from layer names and the shapes on the wall layers. The same
drawing holds evidence that does not go through those decisions, and a
result that contradicts it is built wrong:

- **the drawn building**: the linework of every layer that is not
  annotation, title block, hatch or furniture by its name
  (:func:`.layer_roles.guess_role`), within an opening's width of the
  plan's walls, doors, windows and floors, closed across openings and its
  holes filled, is the building a person sees; the free space (grown back
  by the robot's radius) covers a fair share of it
  (``SELF_CHECK_MIN_FREE_SHARE``). A room outline on layer 0 beside one
  partition on the wall layer, rooms left out, other views of a sheet
  built as walls: each leaves most of the drawn building outside the free
  space.
- **the walls**: a building's walls take a share of its floor
  (``SELF_CHECK_WALL_SHARE``): a whole floor read as windows or glass with
  a stray line as walls has none (the robot would see through every
  wall), elevations and hatches built as walls far too much.
- **the doors**: the door drawings are used as doors
  (``SELF_CHECK_MIN_DOORS_USED``): where most are not, the rooms behind
  them are lost or sealed.
- **doors drawn elsewhere**: where the map found no door, the drawing
  draws none on any layer: a door swing (:mod:`.loose_swings`, an arc of a
  door leaf's radius and its leaf) left on a layer read as furniture or of
  no role (not hinged on a wall, so not taken as a door) is one the map
  left out.
- **the doors' size**: where anything here contradicts the drawing and
  its door drawings are a median width no door has, the drawing is at a
  fraction of its size (no unit mends it): the refusal names the
  ``--scale`` that makes them doors' width first.
- **the rooms are reachable**: where the plan's doors were found and the
  drawing says where its rooms are (walls enclosing them, room outlines,
  room polygons), no part
  of the free space larger than a sliver (``ROOM_PART_MIN_AREA``) is cut
  off from the rest: a door joins the rooms it opens.

:func:`check_against_drawing` returns what contradicts the drawing, each
with the option that would fix it; :func:`enforce` refuses the map
(:class:`~mapkit.errors.InconsistentDrawingError`, exit 2, no output)
unless the user passed ``--accept-inconsistent``, which writes it with a
warning.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy import ndimage

from mapkit.errors import InconsistentDrawingError
from mapkit.importers.dxf.layer_roles import guess_role, is_zone_layer
from mapkit.importers.dxf.loose_swings import find_swings
from mapkit.importers.dxf.openings import door_strokes, drawing_items
from mapkit.importers.dxf.strokes import PlanDrawing
from mapkit.importers.dxf.units import scale_from_gaps
from mapkit.scene import Scene
from mapkit.shapes import polygon_parts
from mapkit.tolerances import (DOOR_REACH_SLACK, DOOR_UNITS_MIN_DOORS, MAX_FLOOR_AREA_M2, OUTLINE_MAX_GAP, ROOM_PART_MIN_AREA,
                               SELF_CHECK_CELL_M, SELF_CHECK_MIN_DOORS_USED, SELF_CHECK_MIN_FREE_SHARE,
                               SELF_CHECK_WALL_SHARE, TYPICAL_DOOR_WIDTH, ZERO)

#: Roles whose layers are building geometry (the rest is annotation).
_DRAWN_ROLES = ("walls", "doors", "windows", "floor", None)


@dataclass(frozen=True)
class Inconsistency:
    """One way a scene contradicts its drawing: ``what`` (a clause) and
    ``fix`` (the options that would mend it, e.g. ``("--walls LAYER",)``)."""

    what: str
    fix: tuple[str, ...]


@dataclass(frozen=True)
class Evidence:
    """What the drawing shows beside what was built (areas m2)."""

    drawn_m2: float
    free_m2: float
    walls_m2: float
    doors_drawn: int
    doors_used: int


def gather_evidence(scene: Scene, drawing: PlanDrawing, robot_radius: float = 0.0) -> Evidence:
    """The drawing's own evidence about ``scene`` (see the module docstring).
    ``free_m2`` is the free space grown back by ``robot_radius`` (the
    floor the rooms take, not where the robot's centre may be)."""
    doors, _ = door_strokes(drawing.role("doors"))  # less dimension chains and outlines on the door layers
    doors_drawn = len(drawing_items(doors)) if doors else 0
    return Evidence(
        drawn_m2=drawn_building_area(drawing),
        free_m2=float(scene.free_space.buffer(robot_radius, join_style="mitre").area if robot_radius > ZERO.distance
                      else scene.free_space.area),
        walls_m2=float(scene.walls.area),
        doors_drawn=doors_drawn,
        doors_used=sum(o.kind == "door" for o in scene.openings),
    )


def drawn_building_area(drawing: PlanDrawing) -> float:
    """Area, m2, of the building the plan's linework draws: the strokes of
    every layer that is building geometry (the roles' and those whose name
    says nothing; not annotation, hatch, furniture, title block) on a grid
    of ``SELF_CHECK_CELL_M`` cells, closed across gaps up to
    ``OUTLINE_MAX_GAP`` (doorways, windows, an entrance), holes filled;
    only the pieces holding the plan's walls (a sheet's other views and a
    site plan apart from the building do not count). 0 without walls."""
    walls = drawing.role("walls")
    if not walls:
        return 0.0
    plan = [s for role in ("walls", "doors", "windows", "floor") for s in drawing.role(role)]
    others = [s for layer, group in drawing.ignored.items() if guess_role(layer) in _DRAWN_ROLES for s in group]
    points = np.concatenate([s.coords for s in plan])
    # The building is where its walls, doors, windows and floors are drawn,
    # and what is drawn within an opening's width of them (a room outline on
    # another layer): a site plan, a sheet's other views farther out are not.
    lo, hi = points.min(axis=0) - OUTLINE_MAX_GAP, points.max(axis=0) + OUTLINE_MAX_GAP
    # A sheet larger than the largest floor a map is built for gets larger
    # cells: the grid never holds more than that floor at SELF_CHECK_CELL_M.
    cell = SELF_CHECK_CELL_M * max(1.0, float(np.sqrt(np.prod(hi - lo) / MAX_FLOOR_AREA_M2)))
    shape = tuple(int(v) + 1 for v in np.ceil((hi - lo) / cell))
    grid = np.zeros(shape, dtype=bool)
    for s in plan + others:
        _draw(grid, s.coords, s.closed, lo, cell)
    radius = max(1, int(np.ceil(OUTLINE_MAX_GAP / 2.0 / cell)))
    disk = _disk(radius)
    padded = np.pad(grid, radius + 1)
    closed = ndimage.binary_erosion(ndimage.binary_dilation(padded, disk), disk)[radius + 1:-radius - 1, radius + 1:-radius - 1]
    filled = ndimage.binary_fill_holes(closed | grid)
    labels, _ = ndimage.label(filled)
    wall_grid = np.zeros(shape, dtype=bool)
    for s in walls:
        _draw(wall_grid, s.coords, s.closed, lo, cell)
    kept = np.unique(labels[wall_grid & filled])
    kept = kept[kept > 0]
    return float(np.isin(labels, kept).sum()) * cell * cell


def _draw(grid: np.ndarray, coords: np.ndarray, closed: bool, lo: np.ndarray, cell: float) -> None:
    """Mark the cells of ``grid`` (origin ``lo``, ``cell`` metres) a polyline passes through."""
    xy = np.asarray(coords, dtype=float)[:, :2]
    if closed:
        xy = np.vstack([xy, xy[:1]])
    a, b = xy[:-1], xy[1:]
    steps = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / (0.5 * cell))).astype(int)
    t = np.concatenate([np.linspace(0.0, 1.0, n + 1) for n in steps])
    seg = np.repeat(np.arange(len(a)), steps + 1)
    pts = a[seg] + (b[seg] - a[seg]) * t[:, None]
    ij = np.floor((pts - lo) / cell).astype(int)
    inside = ((ij >= 0) & (ij < np.array(grid.shape))).all(axis=1)
    grid[ij[inside, 0], ij[inside, 1]] = True


def _disk(radius: int) -> np.ndarray:
    y, x = np.ogrid[-radius:radius + 1, -radius:radius + 1]
    return x * x + y * y <= radius * radius


def check_against_drawing(scene: Scene, drawing: PlanDrawing, robot_radius: float = 0.0) -> list[Inconsistency]:
    """What in ``scene`` contradicts its ``drawing`` (empty: consistent);
    ``robot_radius`` (m) is the margin the free space was shrunk by.
    A scene without free space or walls is not judged here: the
    reconstruction refuses it itself."""
    if scene.free_space.is_empty or scene.walls.is_empty:
        return []
    ev = gather_evidence(scene, drawing, robot_radius)
    several_plans = len(scene.info.get("plans", [])) > 1
    plan_fix = ("--plan N",) if several_plans else ("--walls LAYER", "--floor LAYER")
    found = []
    floor = ev.walls_m2 + ev.free_m2
    lo, hi = SELF_CHECK_WALL_SHARE
    if ev.walls_m2 < lo * floor:
        found.append(Inconsistency(
            f"walls are {ev.walls_m2:.1f} m2 for {ev.free_m2:.0f} m2 of floor ({100 * ev.walls_m2 / floor:.2g} % "
            f"of the floor, a building's walls take {100 * lo:g} % or more): the plan's walls are on a layer read "
            "as something else", ("--walls LAYER",)))
    elif ev.walls_m2 > hi * floor:
        found.append(Inconsistency(
            f"walls are {ev.walls_m2:.0f} m2, {100 * ev.walls_m2 / floor:.0f} % of the floor (a building's walls take "
            f"under {100 * hi:g} %): hatches, other views or furniture built as walls", plan_fix))
    if ev.drawn_m2 > 0 and ev.free_m2 < SELF_CHECK_MIN_FREE_SHARE * ev.drawn_m2:
        found.append(Inconsistency(
            f"the free space is {ev.free_m2:.0f} m2 (grown back by the robot's radius), "
            f"{100 * ev.free_m2 / ev.drawn_m2:.0f} % of the "
            f"{ev.drawn_m2:.0f} m2 the drawing's building covers (rooms take {100 * SELF_CHECK_MIN_FREE_SHARE:.0f} % "
            "or more of it): rooms left out, or other views built as walls", plan_fix))
    if ev.doors_drawn >= DOOR_UNITS_MIN_DOORS and ev.doors_used < SELF_CHECK_MIN_DOORS_USED * ev.doors_drawn:
        found.append(Inconsistency(
            f"{ev.doors_used} of the {ev.doors_drawn} door drawings are used as doors (each door is one or two "
            "drawings): the rooms behind the others are lost", ("--doors LAYER", "--walls LAYER", "--units")))
    swings = _swings_elsewhere(drawing) if ev.doors_used == 0 else {}
    if swings:
        found.append(Inconsistency(
            f"the map found no door, but the drawing draws {sum(swings.values())} door swing(s) on "
            + ", ".join(f"'{layer}' ({n})" for layer, n in sorted(swings.items())), ("--doors LAYER",)))
    # Where the drawing says where its rooms are (walls enclosing them, room
    # outlines or room polygons): a floor outline of a pavilion's podium, cut
    # by glass and freestanding walls, says nothing of rooms.
    rooms_drawn = scene.info.get("interior") in ("enclosed", "room outlines") or any(
        is_zone_layer(s.layer) for s in drawing.role("floor"))
    cut_off = _rooms_cut_off(scene, robot_radius) if ev.doors_used and rooms_drawn else []
    if cut_off:
        found.append(Inconsistency(
            f"{len(cut_off)} room(s) of {ROOM_PART_MIN_AREA:g} m2 or more ({', '.join(f'{a:.0f}' for a in cut_off[:4])}"
            f"{' ...' if len(cut_off) > 4 else ''} m2) are cut off from the rest with no door found at them, though "
            "the plan's other doors were found", ("--doors LAYER",)))
    scale = door_scale(drawing) if found else None
    if scale is not None:
        # The doors say the whole drawing is at a fraction of its size: no layer choice mends that.
        count, median, times = scale
        found.insert(0, Inconsistency(
            f"its {count} door drawings are a median {median:.2g} m wide, no door's width: if they are doors about "
            f"{TYPICAL_DOOR_WIDTH:g} m wide, it is drawn at about 1/{times:g} of its size", (f"--scale {times:g}",)))
    return found


def door_scale(drawing: PlanDrawing) -> tuple[int, float, float] | None:
    """``(count, median width m, scale)`` of the plan's door drawings when
    their median width is no door's width (``DOOR_WIDTH_PLAUSIBLE``; judged
    from ``DOOR_UNITS_MIN_DOORS`` drawings): the scale that makes it
    ``TYPICAL_DOOR_WIDTH`` (:func:`.units.scale_from_gaps`: an estimate, so
    named in a refusal, never applied). Each drawing's width is the longer
    side of its minimum rotated rectangle (a leaf and its swing, a line, a
    block)."""
    doors, _ = door_strokes(drawing.role("doors"))
    widths = []
    for item in drawing_items(doors) if doors else []:
        box = shapely.minimum_rotated_rectangle(item)
        xy = np.asarray(box.exterior.coords if box.geom_type == "Polygon" else box.coords, dtype=float)
        widths.append(float(np.hypot(*np.diff(xy, axis=0).T).max()) if len(xy) > 1 else 0.0)
    return scale_from_gaps(widths)


def _swings_elsewhere(drawing: PlanDrawing) -> dict[str, int]:
    """Door swings (:func:`.loose_swings.find_swings`, a leaf any stroke
    that reaches the hinge and the arc's end) on the layers the plan left
    out (furniture, layers of no role), per layer."""
    out: dict[str, int] = {}
    for layer, strokes in drawing.ignored.items():
        n = len(find_swings(strokes, leaf_radii=np.inf))
        if n:
            out[layer] = n
    return out


def _rooms_cut_off(scene: Scene, robot_radius: float) -> list[float]:
    """Areas (m2, largest first) of the free space's parts beyond its
    largest that are more than a sliver (``ROOM_PART_MIN_AREA``) and that
    no door joins to anything: rooms whose doors were not found.

    A door joins a part when its opening comes within ``robot_radius`` plus
    ``DOOR_REACH_SLACK`` of it and also of another part (a door too narrow
    for the robot) or reaches the building's outside (an entrance). A door
    that touches one part only opens nothing: its opening was put beside
    the doorway (along the open leaf), and the room behind it is lost."""
    parts = sorted(polygon_parts(scene.free_space), key=lambda p: -p.area)
    doors = [o.footprint for o in scene.openings if o.kind == "door"]
    reach = robot_radius + DOOR_REACH_SLACK
    outside = _outside(scene, reach)
    joining = [d for d in doors
               if d.distance(outside) <= DOOR_REACH_SLACK or sum(p.distance(d) <= reach for p in parts) >= 2]
    return [float(p.area) for p in parts[1:]
            if p.area >= ROOM_PART_MIN_AREA and not any(p.distance(d) <= reach for d in joining)]


def _outside(scene: Scene, reach: float):
    """The building's outer boundary (lines): the rim of its walls,
    openings and free space (grown back by ``reach``), holes filled."""
    drawn = shapely.union_all([scene.walls, scene.free_space.buffer(reach),
                               *(o.footprint for o in scene.openings)])
    shells = [shapely.Polygon(p.exterior) for p in polygon_parts(drawn)]
    return shapely.union_all(shells).boundary


def enforce(scene: Scene, drawing: PlanDrawing, robot_radius: float, accept: bool, warn) -> None:
    """Refuse ``scene`` (:class:`~mapkit.errors.InconsistentDrawingError`,
    one line: what contradicts the drawing and which options would fix it)
    when :func:`check_against_drawing` finds anything, unless ``accept``
    (``--accept-inconsistent``): then ``warn(message)`` and go on."""
    found = check_against_drawing(scene, drawing, robot_radius)
    if not found:
        return
    fixes = list(dict.fromkeys(option for f in found for option in f.fix))
    message = ("the map contradicts its drawing: " + "; ".join(f.what for f in found) + "; fix with "
               + " or ".join(fixes) + " (check with 'mapkit layers' and 'mapkit preview')")
    if accept:
        warn(message + "; written anyway (--accept-inconsistent)")
        return
    raise InconsistentDrawingError(message + ", or write it anyway with --accept-inconsistent", scene)
