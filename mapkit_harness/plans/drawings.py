"""Synthetic DXF floor plans drawn the way architects draw them, with known answers.

The companion of :mod:`mapkit_harness.plans.buildings` (which makes shapely
scenes and maps): these functions write DXF drawings through ezdxf, for the importer's
tests and for ``tools/bench_build.py``. Each returns a :class:`PlanFacts`
holding what the drawing is known to contain (free floor area before the
robot radius, door count), so tests assert against it rather than against
what the importer happens to produce.

Conventions of the drawings (metres, ``$INSUNITS`` 6, z up):

- walls are closed LWPOLYLINE outlines of wall pieces (one per stretch of
  wall between openings) and of piers/columns, overlapping where pieces
  meet, as CAD users draw them;
- doors are block INSERTs placed at the hinge: the block's leaf stands on
  local +y at the hinge and its swing arc runs from the latch (local +x,
  the door's width away) round to the open leaf; rotated to the wall and
  mirrored (x scale -1) for the other hand;
- layers use AIA-style names with numbers (``A-210 G - Existing Structure 4``).

Plans:

- :func:`office_grid` — ``n x n`` rooms of ``room`` metres with a door in
  every interior wall of each room (the generated 100-room office of
  issue 27 at ``n = 10``);
- :func:`open_office` — an open-plan floor of about 600 m2 with the traits
  of the real office of issue 27: facade pieces and piers with no closed
  outline (window gaps left open in the drawing), a grid of columns,
  meeting rooms and cellular offices in solid partitions with door blocks,
  virtual partitions, furniture and text.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import ezdxf
import numpy as np
import shapely
from shapely.geometry import box

from mapkit_harness.plans.grid_layout import RoomGridLayout, stretches_between

#: Layer names of the open-plan office, as the real drawing spells them.
STRUCTURE = "A-210 G - Existing Structure 4"
PARTITIONS = "A-320G - Permanent Solid Partitions 12"
VIRTUAL = "I-321G - Virtual Partition 18"
DOORS = "A-325G - Internal Doors 6"
FURNITURE = "Furniture 4"
TEXT = "A-900 Room Names"

LEAF = 0.04  # door leaf thickness, m


@dataclass
class PlanFacts:
    """What a synthetic drawing holds, known by construction.

    - ``walls``: shapely (Multi)Polygon of every wall solid (partitions,
      piers, columns), metres;
    - ``interior``: the building's inside with door gaps closed, metres;
      ``free_area`` = area of ``interior - walls`` (m2, before any robot radius);
    - ``doors``: number of door drawings, each in a wall gap;
    - ``rooms``: number of rooms, closed by walls and doors.
    """

    walls: object
    interior: object
    doors: int
    rooms: int
    extra: dict = field(default_factory=dict)

    @property
    def free_area(self) -> float:
        return float(self.interior.difference(self.walls).area)


def new_document():
    """An R2010 drawing in metres."""
    doc = ezdxf.new("R2010")
    doc.units = ezdxf.units.M
    doc.header["$INSUNITS"] = 6
    doc.header["$MEASUREMENT"] = 1
    return doc


def define_door_block(doc, width: float, name: str | None = None) -> str:
    """A door block: hinge at the origin, closed leaf along +x, opening into +y.

    The leaf is drawn open (a thin rectangle standing on +y at the hinge),
    the swing arc runs from the latch ``(width, 0)`` to the open leaf's end
    ``(0, width)``; everything on layer 0 so the insert's layer applies."""
    name = name or f"DOOR_{round(width * 1000)}"
    if name not in doc.blocks:
        blk = doc.blocks.new(name, base_point=(0, 0))
        blk.add_lwpolyline([(0, 0), (-LEAF, 0), (-LEAF, width), (0, width)], close=True)
        blk.add_arc((0, 0), width, 0, 90)
    return name


def add_door(msp, block: str, hinge, latch, swing_side: int, layer: str):
    """Insert ``block`` at ``hinge`` so that it closes onto ``latch`` and swings
    to ``swing_side`` (+1: left of hinge->latch, -1: right, by mirroring)."""
    ux, uy = latch[0] - hinge[0], latch[1] - hinge[1]
    if swing_side > 0:
        rotation, xscale = math.degrees(math.atan2(uy, ux)), 1.0
    else:  # mirrored in local x: the block's +x points from the latch back to the hinge
        rotation, xscale = math.degrees(math.atan2(-uy, -ux)), -1.0
    return msp.add_blockref(block, hinge, dxfattribs={"layer": layer, "rotation": rotation % 360.0, "xscale": xscale})


def add_rect(msp, x0, y0, x1, y1, layer: str):
    """A closed LWPOLYLINE rectangle (a wall piece, a pier, a desk)."""
    msp.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True, dxfattribs={"layer": layer})
    return box(min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))


# --------------------------------------------------------------------------
# (a) the generated office: n x n rooms with doors


def office_grid(path: str | Path, n: int = 10, room: float = 5.0, thickness: float = 0.15, door: float = 0.9,
                wall_layer: str = "A-WALL", door_layer: str = "A-DOOR") -> PlanFacts:
    """Write an office of ``n x n`` rooms of ``room`` metres (walls ``thickness``
    thick, centred on the room grid, the outer ones inside it) to ``path``.

    Every interior wall of a room has a door of width ``door``: one per room
    in each wall between columns (at the room's middle) and in each wall
    between rows (at 0.3 of the room), so every room is reached. Walls are
    closed outlines of the pieces between doors; doors are block inserts at
    the hinge, turned to their wall and mirrored every other one. The
    layout is :class:`~mapkit_harness.plans.grid_layout.RoomGridLayout`'s.
    """
    layout = RoomGridLayout((n, n), (room, room), thickness, door)
    doc = new_document()
    msp = doc.modelspace()
    block = define_door_block(doc, door)
    walls, gaps = [], []
    # Each wall's pieces, then its doors, wall after wall: the drawing's order.
    for wall in layout.walls():
        walls += [add_rect(msp, *piece, wall_layer) for piece in wall.pieces]
        for doorway in wall.doorways:
            add_door(msp, block, doorway.hinge, doorway.latch, doorway.swing_side, door_layer)
            gaps.append(box(*doorway.rect))
    doc.saveas(path)
    wall_geom = shapely.union_all(walls)
    interior = box(*layout.outline)
    return PlanFacts(wall_geom, interior, len(gaps), n * n, {"door_gaps": gaps})


# --------------------------------------------------------------------------
# (b) the open-plan office


def open_office(path: str | Path, width: float = 30.0, depth: float = 20.0, pier_spacing: float = 1.5,
                seed: int = 0) -> PlanFacts:
    """Write an open-plan office floor of ``width x depth`` metres to ``path``.

    - Facade (``STRUCTURE``): wall pieces 0.3 m thick between piers every
      6 m bays, with window gaps 1.8 m wide left open in the drawing
      (no glazing layer, so no closed outline) and a double entrance door;
      piers 0.6 x 0.8 m standing inwards at every bay line and small ones
      (0.24 x 0.6 m) every ``pier_spacing`` metres along the wall pieces;
      round columns 0.5 m across on a grid.
    - Cellular rooms (``PARTITIONS``, 0.1 m): a row of meeting rooms along
      the north facade and a core of three small rooms, each with a door
      block (``DOORS``) at the hinge, rotated and mirrored.
    - ``VIRTUAL`` lines dividing the open plan into zones; desks, chairs
      (blocks) on ``FURNITURE``; room names as MTEXT on ``TEXT``.

    ``seed`` moves the desks only. The known interior is the facade's inner
    rectangle (the window gaps are closed across their width).
    """
    rng = np.random.default_rng(seed)
    doc = new_document()
    msp = doc.modelspace()
    door_block = define_door_block(doc, 0.9)
    wide_block = define_door_block(doc, 0.8)
    chair = doc.blocks.new("CHAIR")
    chair.add_lwpolyline([(-0.25, -0.25), (0.25, -0.25), (0.25, 0.25), (-0.25, 0.25)], close=True)
    chair.add_circle((0, 0), 0.2)
    t, bay = 0.3, 6.0
    walls, gaps, door_gaps = [], [], []
    doors = 0

    # ---- facade: pieces between piers, a window gap in each bay
    entrance = (width / 2 - 0.8, width / 2 + 0.8)  # double door on the south facade
    for horizontal, fixed, (y0, y1) in ((True, 0.0, (0.0, t)), (True, depth, (depth - t, depth)),
                                        (False, 0.0, (0.0, t)), (False, width, (width - t, width))):
        length = width if horizontal else depth
        holes = []
        k = 0
        while (k + 1) * bay <= length + 1e-9:
            mid = (k + 0.5) * bay
            holes.append((mid - 0.9, mid + 0.9))
            k += 1
        if horizontal and fixed == 0.0:  # the entrance replaces the window of its bay
            holes = [g for g in holes if g[1] < entrance[0] or g[0] > entrance[1]] + [entrance]
        for a, b in stretches_between(0.0, length, holes):
            walls.append(add_rect(msp, a, y0, b, y1, STRUCTURE) if horizontal else add_rect(msp, y0, a, y1, b, STRUCTURE))
        for a, b in holes:
            if (a, b) != entrance or not horizontal or fixed != 0.0:
                gaps.append(box(a, y0, b, y1) if horizontal else box(y0, a, y1, b))
        # Piers standing inwards from the facade: big ones at every bay line,
        # small mullion piers every ``pier_spacing`` along the wall pieces.
        inward = 1 if fixed == 0.0 else -1
        centres = [(k * bay, 0.3, 0.5) for k in range(1, int(length // bay) + 1)]
        for a, b in stretches_between(0.0, length, holes):
            centres += [(c, 0.12, 0.3) for c in np.arange(a + 0.4, b - 0.3, pier_spacing) if
                        all(abs(c - k * bay) > 0.6 for k in range(int(length // bay) + 1))]
        for c, half, reach in centres:
            if not (t + half < c < length - t - half):
                continue
            p0, p1 = (y0, y1 + reach) if inward > 0 else (y0 - reach, y1)
            walls.append(add_rect(msp, c - half, p0, c + half, p1, STRUCTURE) if horizontal
                         else add_rect(msp, p0, c - half, p1, c + half, STRUCTURE))
    # entrance: two leaves hinged at the jambs, swinging in
    add_door(msp, wide_block, (entrance[0], t), (entrance[0] + 0.8, t), 1, DOORS)
    add_door(msp, wide_block, (entrance[1], t), (entrance[1] - 0.8, t), -1, DOORS)
    door_gaps.append(box(entrance[0], 0.0, entrance[1], t))
    doors += 1

    # ---- meeting rooms along the north facade: 5 m deep, partitions 0.1 m
    pt = 0.1
    north = depth - t
    front = north - 5.0
    xs = [t, 6.0, 12.0, 18.0]  # room walls; east of 18 m stays open plan
    for a, b in stretches_between(xs[0], xs[-1] + pt / 2, [(x + 1.0, x + 1.9) for x in xs[:-1]]):
        walls.append(add_rect(msp, a, front - pt / 2, b, front + pt / 2, PARTITIONS))
    for x in xs[1:]:
        walls.append(add_rect(msp, x - pt / 2, front - pt / 2, x + pt / 2, north, PARTITIONS))
    for k, x in enumerate(xs[:-1]):
        # On the partition's south face: swinging into the room (north) or out of it, hinge at either jamb.
        a, b, y = (x + 1.0, x + 1.9, front - pt / 2)
        if k % 2 == 0:
            add_door(msp, door_block, (a, y), (b, y), 1, DOORS)
        else:
            add_door(msp, door_block, (b, y), (a, y), 1, DOORS)
        door_gaps.append(box(x + 1.0, front - pt / 2, x + 1.9, front + pt / 2))
        doors += 1
        msp.add_mtext(f"Meeting {k + 1}", dxfattribs={"layer": TEXT, "insert": (x + 2.0, front + 2.5), "char_height": 0.3})

    # ---- core: three small rooms in the middle, doors on the south side
    cx0, cy0, cx1, cy1 = 12.0, 5.0, 18.0, 9.0
    core_doors = [(cx0 + 0.5, cx0 + 1.4), (cx0 + 2.5, cx0 + 3.4), (cx0 + 4.5, cx0 + 5.4)]
    for a, b in stretches_between(cx0 - pt / 2, cx1 + pt / 2, core_doors):
        walls.append(add_rect(msp, a, cy0 - pt / 2, b, cy0 + pt / 2, PARTITIONS))
    walls.append(add_rect(msp, cx0 - pt / 2, cy1 - pt / 2, cx1 + pt / 2, cy1 + pt / 2, PARTITIONS))
    for x in (cx0, cx0 + 2.0, cx0 + 4.0, cx1):
        walls.append(add_rect(msp, x - pt / 2, cy0 - pt / 2, x + pt / 2, cy1 + pt / 2, PARTITIONS))
    for k, (a, b) in enumerate(core_doors):
        # hinge on the left or right jamb, door swinging out of the room (mirrored every other one)
        if k % 2:
            add_door(msp, door_block, (b, cy0 - pt / 2), (a, cy0 - pt / 2), 1, DOORS)
        else:
            add_door(msp, door_block, (a, cy0 - pt / 2), (b, cy0 - pt / 2), -1, DOORS)
        door_gaps.append(box(a, cy0 - pt / 2, b, cy0 + pt / 2))
        doors += 1

    # ---- columns on the bay grid, clear of the rooms
    rooms_area = shapely.union_all([box(xs[0], front, xs[-1], north), box(cx0, cy0, cx1, cy1)]).buffer(0.5)
    for cxk in np.arange(bay, width - 1.0, bay):
        for cyk in np.arange(bay * 0.75, depth - 1.0, bay * 0.75):
            # Round columns, as open-plan floors often have: their flattened
            # outlines put many short edges in every view.
            col = shapely.Point(cxk, cyk).buffer(0.25, quad_segs=16)
            if col.intersects(rooms_area):
                continue
            msp.add_circle((cxk, cyk), 0.25, dxfattribs={"layer": STRUCTURE})
            walls.append(col)

    # ---- open-plan zones: virtual partitions (no wall on site)
    for x in (6.0, 24.0):
        msp.add_line((x, t), (x, front - 0.5), dxfattribs={"layer": VIRTUAL})
    msp.add_line((18.0, 10.0), (width - t, 10.0), dxfattribs={"layer": VIRTUAL})

    # ---- furniture: desks with chairs in the open plan
    solid = shapely.union_all(walls)
    furniture = []
    for x in np.arange(1.5, width - 2.0, 3.0):
        for y in np.arange(1.5, depth - 6.0, 2.5):
            dx, dy = rng.uniform(-0.2, 0.2, 2)
            desk = box(x + dx, y + dy, x + dx + 1.6, y + dy + 0.8)
            if desk.buffer(0.6).intersects(solid) or desk.intersects(rooms_area):
                continue
            furniture.append(add_rect(msp, *desk.bounds, FURNITURE))
            msp.add_blockref("CHAIR", (x + dx + 0.8, y + dy - 0.35), dxfattribs={"layer": FURNITURE, "rotation": float(rng.uniform(0, 360))})
    msp.add_mtext("Open plan", dxfattribs={"layer": TEXT, "insert": (4.0, 4.0), "char_height": 0.4})
    doc.saveas(path)
    interior = box(t, t, width - t, depth - t)
    return PlanFacts(shapely.union_all(walls), interior, doors, 7,
                     {"window_gaps": gaps, "door_gaps": door_gaps, "desks_and_lines": furniture})




# --------------------------------------------------------------------------
# Small plans of the other classes of issue 27


def zone_plan(path: str | Path, rooms: tuple[int, int] = (3, 2), room: float = 4.0, wall: float = 0.2) -> PlanFacts:
    """A plan drawn as room polygons: each room's space boundary a closed
    polyline on ``ABY_Zone_ZIND`` (``rooms`` = (nx, ny) rooms of ``room``
    metres, ``wall`` apart), the building's outline on ``ABY_Contour_Facade``
    at the walls' outer faces, French room names as MTEXT, no wall layer.
    The free space is the rooms."""
    doc = new_document()
    msp = doc.modelspace()
    nx, ny = rooms
    zones = []
    names = ["Séjour", "Cuisine", "Chambre 1", "Chambre 2", "Bureau", "Salle de bains", "Entrée", "Cellier"]
    for i in range(nx):
        for j in range(ny):
            x0, y0 = wall + i * (room + wall), wall + j * (room + wall)
            zones.append(add_rect(msp, x0, y0, x0 + room, y0 + room, "ABY_Zone_ZIND"))
            msp.add_mtext(names[(i * ny + j) % len(names)],
                          dxfattribs={"layer": "ABY_Texte_Pieces", "insert": (x0 + 0.5, y0 + room / 2), "char_height": 0.25})
    w, h = nx * (room + wall) + wall, ny * (room + wall) + wall
    msp.add_lwpolyline([(0, 0), (w, 0), (w, h), (0, h)], close=True, dxfattribs={"layer": "ABY_Contour_Facade"})
    doc.saveas(path)
    interior = shapely.union_all(zones)
    walls = box(0, 0, w, h).difference(interior)
    return PlanFacts(walls, interior, 0, nx * ny)


def nested_room(path: str | Path, width: float = 6.0, depth: float = 4.0, thickness: float = 0.2,
                furniture: bool = True) -> PlanFacts:
    """One room whose wall is drawn as two nested closed polylines (its outer
    and inner faces) on ``A-WALL``, with a table and text on other layers."""
    doc = new_document()
    msp = doc.modelspace()
    t = thickness
    add_rect(msp, 0, 0, width, depth, "A-WALL")
    add_rect(msp, t, t, width - t, depth - t, "A-WALL")
    if furniture:
        add_rect(msp, width / 2 - 0.6, depth / 2 - 0.4, width / 2 + 0.6, depth / 2 + 0.4, "A-FURN")
        msp.add_text("Living", dxfattribs={"layer": "A-ANNO-TEXT", "insert": (1.0, 1.0), "height": 0.2})
    doc.saveas(path)
    return PlanFacts(box(0, 0, width, depth).difference(box(t, t, width - t, depth - t)),
                     box(t, t, width - t, depth - t), 0, 1)


__all__ = ["DOORS", "FURNITURE", "PARTITIONS", "PlanFacts", "STRUCTURE", "TEXT", "VIRTUAL", "add_door", "add_rect",
           "define_door_block", "nested_room", "new_document", "office_grid", "open_office", "zone_plan"]
