"""Small DXF drawings that a layer-name reading builds wrong, for the self-check's tests.

Each reproduces a kind of failure seen on real drawings (issue 44), in a
plan small enough to build in a second: :func:`row_of_rooms` (a row of
4 x 4 m rooms off a 2 m corridor, single-line walls, a door swing in each
room's corridor wall) with its walls on a layer named for windows, its
door drawings off their walls, its header in the wrong units;
:func:`room_outline_on_layer_0` (a room outlined on layer 0, one closet of
partitions on the wall layer); :func:`plan_beside_elevation` (a plan with
an elevation of its facade and its framing plan beside it on the same layer);
:func:`solid_walls_in_metres` (thick double-line walls, no opening drawn,
a header in mm); :func:`doors_with_the_furniture` (door swings drawn on
the furniture layer, beside chairs' arcs); :func:`room_polygons_off_an_open_corridor`
and :func:`rooms_beside_doorless_spaces` (room polygons for some rooms;
a store with no door drawn).
"""

from __future__ import annotations

from pathlib import Path

import ezdxf
import numpy as np


def row_of_rooms(path: str | Path, n: int = 6, wall_layer: str = "A-WALL", door_layer: str = "A-DOOR",
                 insunits: int = 6, unit_per_m: float = 1.0, door_offset: float = 0.0,
                 stray_wall_layer: str | None = None, lost_doors: int = 0, measurement: int | None = None,
                 wall_thickness: float = 0.0) -> Path:
    """``n`` rooms of 4 x 4 m in a row off a corridor 2 m wide (the plan
    ``4 n`` x 6 m), single-line walls on ``wall_layer``, each room's 0.9 m
    door a leaf and its swing on ``door_layer`` in a gap of the corridor
    wall; drawn ``unit_per_m`` drawing units to the metre under the header
    code ``insunits``. ``door_offset`` (m) > 0 draws the doors that far
    into the rooms, off an unbroken corridor wall (door drawings no wall
    gap holds), for every room or, with ``lost_doors`` > 0, for that many
    rooms at the east end; ``stray_wall_layer`` adds one short line on
    that layer (a wall layer holding almost nothing); ``measurement`` sets
    the header's $MEASUREMENT (0: imperial); ``wall_thickness`` (m) > 0
    draws the outer walls' inner faces too, that far inside the outline
    (double-line outer walls)."""
    k = unit_per_m
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = insunits
    if measurement is not None:
        doc.header["$MEASUREMENT"] = measurement
    msp = doc.modelspace()
    wall, door = {"layer": wall_layer}, {"layer": door_layer}
    w = 4.0
    msp.add_lwpolyline([(0, 0), (n * w * k, 0), (n * w * k, 6 * k), (0, 6 * k)], close=True, dxfattribs=wall)
    if wall_thickness > 0:
        t = wall_thickness
        msp.add_lwpolyline([(-t * k, -t * k), ((n * w + t) * k, -t * k), ((n * w + t) * k, (6 + t) * k),
                            (-t * k, (6 + t) * k)], close=True, dxfattribs=wall)
    for i in range(1, n):
        msp.add_line((i * w * k, 0), (i * w * k, 4 * k), dxfattribs=wall)
    for i in range(n):
        x0, x1 = i * w * k, (i + 1) * w * k
        hinge = x0 + 1.0 * k
        offset = door_offset if not lost_doors or i >= n - lost_doors else 0.0
        if offset > 0:
            msp.add_line((x0, 4 * k), (x1, 4 * k), dxfattribs=wall)
        else:
            msp.add_line((x0, 4 * k), (hinge, 4 * k), dxfattribs=wall)
            msp.add_line((hinge + 0.9 * k, 4 * k), (x1, 4 * k), dxfattribs=wall)
        y = (4.0 - offset) * k
        msp.add_line((hinge, y), (hinge, y - 0.9 * k), dxfattribs=door)  # the leaf, open into the room
        msp.add_arc((hinge, y), 0.9 * k, 270, 360, dxfattribs=door)
    if stray_wall_layer is not None:
        msp.add_line((0.5 * k, 5.0 * k), (0.9 * k, 5.0 * k), dxfattribs={"layer": stray_wall_layer})
    doc.saveas(path)
    return Path(path)


def room_outline_on_layer_0(path: str | Path) -> Path:
    """A room of 8 x 5.5 m outlined on layer 0 (a wall's two faces, 0.2 m
    apart), a 2.5 x 2 m closet in its corner walled by partitions on
    'Wand (neu)' (new walls, the one layer named for walls) with a door
    swing on 'Doors' in the closet's partition, a table on 'Table'
    (olymp's room: only the partition is on a wall layer)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (8, 0), (8, 5.5), (0, 5.5)], close=True)
    msp.add_lwpolyline([(0.2, 0.2), (7.8, 0.2), (7.8, 5.3), (0.2, 5.3)], close=True)
    part = {"layer": "Wand (neu)"}
    # the closet in the room's north-east corner: x 5.3..7.8, y 3.3..5.3, partitions 0.1 m
    msp.add_lwpolyline([(5.2, 3.2), (5.3, 3.2), (5.3, 5.3), (5.2, 5.3)], close=True, dxfattribs=part)
    msp.add_lwpolyline([(5.2, 3.2), (6.0, 3.2), (6.0, 3.3), (5.2, 3.3)], close=True, dxfattribs=part)
    msp.add_lwpolyline([(6.8, 3.2), (7.8, 3.2), (7.8, 3.3), (6.8, 3.3)], close=True, dxfattribs=part)
    msp.add_lwpolyline([(7.8, 3.2), (7.9, 3.2), (7.9, 5.3), (7.8, 5.3)], close=True, dxfattribs=part)
    msp.add_lwpolyline([(5.2, 5.3), (7.9, 5.3), (7.9, 5.4), (5.2, 5.4)], close=True, dxfattribs=part)
    msp.add_line((6.0, 3.25), (6.0, 2.45), dxfattribs={"layer": "Doors"})
    msp.add_arc((6.0, 3.25), 0.8, 270, 360, dxfattribs={"layer": "Doors"})
    msp.add_lwpolyline([(2, 2), (4, 2), (4, 3), (2, 3)], close=True, dxfattribs={"layer": "Table"})
    doc.saveas(path)
    return Path(path)


def plan_beside_elevation(path: str | Path, n: int = 4, gap: float = 1.5) -> Path:
    """:func:`row_of_rooms` (``n`` rooms, walls on 'A-WALL') with, ``gap``
    metres below it on the same layer, an elevation of its long facade: the
    facade's outline 3 m high, a window in each room's bay, and
    weatherboards drawn every 0.15 m, and ``gap`` metres east of it its
    framing plan, beams 0.1 m wide on a 2 m grid (a sheet whose other views
    share the plan's layers, as the Jw_cad sheets of the corpus do)."""
    row_of_rooms(path, n=n)
    doc = ezdxf.readfile(path)
    msp = doc.modelspace()
    wall = {"layer": "A-WALL"}
    width, base = 4.0 * n, -3.0 - gap
    msp.add_lwpolyline([(0, base), (width, base), (width, base + 3), (0, base + 3)], close=True, dxfattribs=wall)
    for i in range(n):
        x = i * 4.0 + 1.4
        msp.add_lwpolyline([(x, base + 0.9), (x + 1.2, base + 0.9), (x + 1.2, base + 2.1), (x, base + 2.1)],
                           close=True, dxfattribs=wall)
    y = base + 0.15
    while y < base + 3.0 - 1e-9:
        msp.add_line((0, y), (width, y), dxfattribs=wall)
        y += 0.15
    # The framing plan to the plan's east: beams 0.1 m wide (double lines) on a 2 m grid over its footprint.
    x0 = width + gap
    for k in range(int(width / 2.0) + 1):
        x = x0 + 2.0 * k
        msp.add_lwpolyline([(x, 0), (x + 0.1, 0), (x + 0.1, 6), (x, 6)], close=True, dxfattribs=wall)
    for y in (0.0, 2.0, 4.0, 5.9):
        msp.add_lwpolyline([(x0, y), (x0 + width + 0.1, y), (x0 + width + 0.1, y + 0.1), (x0, y + 0.1)], close=True,
                           dxfattribs=wall)
    doc.saveas(path)
    return Path(path)


def doors_across_passages(path: str | Path) -> Path:
    """A hall 12 x 4 m (walls on 'Walls', 0.2 m thick double lines) and, on
    'Doors', two doors that close the hall's width between its two long
    walls' faces, where no wall stops (proxy_hoteldieu's entrance doors
    across passages, barcelona's double door between a glass screen's end
    and a wall): at x = 4 a door line 3.6 m long from face to face; at
    x = 8 a double door, two leaves drawn open with their swings, hinged
    on the north wall's face and stopping 0.3 m short of a glass screen
    ('Crystal', along y = 0.6 from the west wall to x = 9) that runs along
    the hall's south side."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    wall = {"layer": "Walls"}
    msp.add_lwpolyline([(-0.2, -0.2), (12.2, -0.2), (12.2, 4.2), (-0.2, 4.2)], close=True, dxfattribs=wall)
    msp.add_lwpolyline([(0, 0), (12, 0), (12, 4), (0, 4)], close=True, dxfattribs=wall)
    msp.add_line((4, 0.0), (4, 4.0), dxfattribs={"layer": "Doors"})
    msp.add_line((0, 0.6), (9, 0.6), dxfattribs={"layer": "Crystal"})
    for hinge, start, end in (((8, 4.0), 270, 360), ((8, 0.9), 0, 90)):
        msp.add_line(hinge, (hinge[0] + 1.55, hinge[1]), dxfattribs={"layer": "Doors"})
        msp.add_arc(hinge, 1.55, start, end, dxfattribs={"layer": "Doors"})
    doc.saveas(path)
    return Path(path)


def tiled_podium(path: str | Path) -> Path:
    """A podium of 12 x 8 m whose floor is a grid of 1 m tiles on
    'Flooring' (barcelona's): the grid's lines run up to a glass screen
    ('Crystal') along its north edge, y = 8, without a line of their own
    there; walls on 'Walls' (single lines) stand along its west and east
    edges (up to 0.5 m short of the glass) and its south edge but for a 5 m
    entrance (x 2..7); a partition at x = 9 (as far north as the west and
    east walls) with a 1 m doorway at y 3..4 and a door swing in it
    ('Doors'); a light box, two glass panes at x = 5 and x = 6 from y = 2
    to y = 6, closed by a freestanding wall along y = 2 and a glass screen
    along y = 6 (each from x = 4 to x = 7), stands on the tiles with no
    door into it."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    floor, wall, glass = {"layer": "Flooring"}, {"layer": "Walls"}, {"layer": "Crystal"}
    for x in range(13):
        msp.add_line((x, 0), (x, 8), dxfattribs=floor)
    for y in range(8):  # no line along y = 8: the glass is there
        msp.add_line((0, y), (12, y), dxfattribs=floor)
    msp.add_line((-0.5, 8), (12.5, 8), dxfattribs=glass)
    msp.add_line((0, 0), (0, 7.5), dxfattribs=wall)
    msp.add_line((12, 0), (12, 7.5), dxfattribs=wall)
    msp.add_line((0, 0), (2, 0), dxfattribs=wall)
    msp.add_line((7, 0), (12, 0), dxfattribs=wall)
    msp.add_line((9, 0), (9, 3), dxfattribs=wall)
    msp.add_line((9, 4), (9, 7.5), dxfattribs=wall)
    msp.add_line((9, 3), (9.9, 3), dxfattribs={"layer": "Doors"})
    msp.add_arc((9, 3), 0.9, 0, 90, dxfattribs={"layer": "Doors"})
    for x in (5, 6):
        msp.add_line((x, 2), (x, 6), dxfattribs=glass)
    msp.add_line((4, 2), (7, 2), dxfattribs=wall)
    msp.add_line((4, 6), (7, 6), dxfattribs=glass)
    doc.saveas(path)
    return Path(path)


def storeys_in_a_frame(path: str | Path, storeys: int = 2, gap: float = 6.0) -> Path:
    """``storeys`` copies of :func:`row_of_rooms` (4 rooms, 16 x 6 m) side
    by side, ``gap`` metres apart, and around them all a frame drawn on
    the window layer 'A-GLAZ' 2 m out (proxy_escaldes' sheet of storeys,
    framed by a polyline on a window layer: read with the first storey, its
    building spans the sheet)."""
    row_of_rooms(path, n=4)
    doc = ezdxf.readfile(path)
    msp = doc.modelspace()
    first = list(msp)
    for k in range(1, storeys):
        for e in first:
            twin = e.copy()
            msp.add_entity(twin)
            twin.translate(k * (16.0 + gap), 0, 0)
    x1 = storeys * 16.0 + (storeys - 1) * gap
    msp.add_lwpolyline([(-2, -2), (x1 + 2, -2), (x1 + 2, 8), (-2, 8)], close=True, dxfattribs={"layer": "A-GLAZ"})
    doc.saveas(path)
    return Path(path)



def leaf_across_its_arc(path: str | Path) -> Path:
    """Two rooms, 5 x 4 and 3 x 4 m, in an 8 x 4 m outline on 'Walls'
    (single lines; the west room's entrance a 1 m door in a gap of the west
    wall), parted by a partition leaning 25 degrees east from x = 5 whose
    doorway, 0.3 to 1.2 m up it, has a line drawn across it (the whole
    partition again); on 'Doors' its 0.9 m door hinged at the doorway's
    lower jamb, the open leaf drawn as two lines along the south wall, the
    second running past the arc's end and cutting it (proxy_escaldes'
    stair lobby doors)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    wall, door = {"layer": "Walls"}, {"layer": "Doors"}
    msp.add_lwpolyline([(0, 1.5), (0, 0), (8, 0), (8, 4), (0, 4), (0, 2.5)], dxfattribs=wall)
    msp.add_line((0, 1.5), (1, 1.5), dxfattribs=door)
    msp.add_arc((0, 1.5), 1.0, 0, 90, dxfattribs=door)
    u = (0.4226, 0.9063)  # the partition's direction, 25 degrees off north

    def along(t: float) -> tuple[float, float]:
        return 5 + t * u[0], t * u[1]

    msp.add_line(along(0), along(0.3), dxfattribs=wall)
    msp.add_line(along(1.2), along(4 / u[1]), dxfattribs=wall)
    msp.add_line(along(0), along(4 / u[1]), dxfattribs=wall)
    hx, hy = along(0.3)
    msp.add_line((hx, hy), (hx + 0.9, hy), dxfattribs=door)
    msp.add_line((hx, hy + 0.04), (hx + 0.95, hy + 0.04), dxfattribs=door)
    msp.add_arc((hx, hy), 0.9, 0, 65, dxfattribs=door)
    doc.saveas(path)
    return Path(path)


def solid_walls_in_metres(path: str | Path, insunits: int = 4, thickness: float = 0.4) -> Path:
    """A house of 9 x 7 m drawn in metres under the header code
    ``insunits`` (4: mm), its outer walls ``thickness`` m thick as two
    closed outlines on 'muratura' and a partition of the same thickness as
    two lines parting it in two rooms; no door and no opening drawn
    (plotpreview: walls hatched on 'muratura', openings on a layer of no
    role)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = insunits
    msp = doc.modelspace()
    wall = {"layer": "muratura"}
    t = thickness
    msp.add_lwpolyline([(0, 0), (9, 0), (9, 7), (0, 7)], close=True, dxfattribs=wall)
    msp.add_lwpolyline([(t, t), (9 - t, t), (9 - t, 7 - t), (t, 7 - t)], close=True, dxfattribs=wall)
    msp.add_line((5, t), (5, 7 - t), dxfattribs=wall)
    msp.add_line((5 + t, t), (5 + t, 7 - t), dxfattribs=wall)
    doc.saveas(path)
    return Path(path)


__all__ = ["doors_across_passages", "leaf_across_its_arc", "plan_beside_elevation", "room_outline_on_layer_0", "row_of_rooms",
           "solid_walls_in_metres", "storeys_in_a_frame",
           "tiled_podium"]


def doors_with_the_furniture(path: str | Path, n: int = 4, hinged: bool = True) -> Path:
    """``n`` rooms of 4 x 4 m in a row off a 2 m corridor, single-line walls
    on 'Walls' with a 0.9 m gap in each room's corridor wall; each door's
    swing on 'Furniture', drawn as one polyline (hinge, the open leaf's tip,
    the arc back to the far jamb: proxy_cityscience's office doors), hinged
    at the gap's jamb or, with ``hinged`` False, 0.5 m into the room, off
    the wall; in each room a round table on 'Furniture' with a chair's
    back, a quarter arc of 0.6 m and a radial line, in its middle (an arc
    of a door's size hinged on no wall)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    wall, furniture = {"layer": "Walls"}, {"layer": "Furniture"}
    w = 4.0
    msp.add_lwpolyline([(0, 0), (n * w, 0), (n * w, 6), (0, 6)], close=True, dxfattribs=wall)
    for i in range(1, n):
        msp.add_line((i * w, 0), (i * w, 4), dxfattribs=wall)
    for i in range(n):
        x0, hinge = i * w, i * w + 1.0
        msp.add_line((x0, 4), (hinge, 4), dxfattribs=wall)
        msp.add_line((hinge + 0.9, 4), (x0 + w, 4), dxfattribs=wall)
        y = 4.0 if hinged else 3.5
        arc = [(hinge + 0.9 * np.sin(t), y - 0.9 * np.cos(t)) for t in np.linspace(0, np.pi / 2, 9)]
        msp.add_lwpolyline([(hinge, y), *arc], dxfattribs=furniture)
        cx, cy = x0 + 2.5, 2.0
        msp.add_circle((cx, cy), 0.5, dxfattribs=furniture)
        msp.add_arc((cx - 1.2, cy), 0.6, 90, 180, dxfattribs=furniture)
        msp.add_line((cx - 1.2, cy), (cx - 1.8, cy), dxfattribs=furniture)
    doc.saveas(path)
    return Path(path)


def room_polygons_off_an_open_corridor(path: str | Path, n: int = 4, polygons: int = 2) -> Path:
    """``n`` rooms of 4 x 4 m in a row off a corridor 2 m wide, single-line
    walls on 'Walls', each room's doorway a 1 m gap in the corridor wall (no
    door drawn); the corridor's west end open to the outside across a
    2.2 m gap between two wall ends that do not face each other (the south
    one ends going north, the north one going west); the first
    ``polygons`` rooms outlined on 'Meeting rooms', a room-polygon layer
    (proxy_learning: room polygons for some rooms, none for the corridor)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    wall, zone = {"layer": "Walls"}, {"layer": "Meeting rooms"}
    w = 4.0
    msp.add_lwpolyline([(0, 4), (0, 0), (n * w, 0), (n * w, 6), (1, 6)], dxfattribs=wall)
    for i in range(n):
        x0 = i * w
        if i:
            msp.add_line((x0, 0), (x0, 4), dxfattribs=wall)
        msp.add_line((x0, 4), (x0 + 1.5, 4), dxfattribs=wall)
        msp.add_line((x0 + 2.5, 4), (x0 + w, 4), dxfattribs=wall)
        if i < polygons:
            msp.add_lwpolyline([(x0, 0), (x0 + w, 0), (x0 + w, 4), (x0, 4)], close=True, dxfattribs=zone)
    doc.saveas(path)
    return Path(path)


def rooms_beside_doorless_spaces(path: str | Path, missed_door: bool = False) -> Path:
    """A 16 x 6 m outline on 'Walls' (single lines), four 4 x 4 m rooms off
    a 2 m corridor; rooms 0 to 2 each entered by a 0.9 m door swing on
    'Doors' in a gap of the corridor wall, the first two outlined on
    'Meeting rooms' (room polygons); room 3 a store with no door drawn; in
    room 0 a column drawn as a 1.6 m square around a 1.4 m one; in room 2,
    beside the store's wall, a toilet stall's door swing hung on no wall
    (proxy_factory: stores, ducts and hollow columns with no door, stall
    doors on partitions not drawn as walls). ``missed_door``: room 2's door
    is drawn 0.5 m into the room off an unbroken corridor wall instead (a
    door the plan draws but no gap holds)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    wall, door, zone = {"layer": "Walls"}, {"layer": "Doors"}, {"layer": "Meeting rooms"}
    msp.add_lwpolyline([(0, 0), (16, 0), (16, 6), (0, 6)], close=True, dxfattribs=wall)
    for i in range(4):
        x0 = 4.0 * i
        if i:
            msp.add_line((x0, 0), (x0, 4), dxfattribs=wall)
        hinge = x0 + 1.0
        if i == 3 or (i == 2 and missed_door):
            msp.add_line((x0, 4), (x0 + 4, 4), dxfattribs=wall)
        else:
            msp.add_line((x0, 4), (hinge, 4), dxfattribs=wall)
            msp.add_line((hinge + 0.9, 4), (x0 + 4, 4), dxfattribs=wall)
        if i < 3:
            y = 3.5 if (i == 2 and missed_door) else 4.0
            msp.add_line((hinge, y), (hinge, y - 0.9), dxfattribs=door)
            msp.add_arc((hinge, y), 0.9, 270, 360, dxfattribs=door)
        if i < 2:
            msp.add_lwpolyline([(x0, 0), (x0 + 4, 0), (x0 + 4, 4), (x0, 4)], close=True, dxfattribs=zone)
    msp.add_lwpolyline([(1.2, 1.2), (2.8, 1.2), (2.8, 2.8), (1.2, 2.8)], close=True, dxfattribs=wall)
    msp.add_lwpolyline([(1.3, 1.3), (2.7, 1.3), (2.7, 2.7), (1.3, 2.7)], close=True, dxfattribs=wall)
    # A stall door in room 2 (x 8-12) by the store's wall at x = 12, hung on no wall: open, 0.2 m off it.
    msp.add_line((11.8, 1.0), (11.0, 1.0), dxfattribs=door)
    msp.add_arc((11.8, 1.0), 0.8, 90, 180, dxfattribs=door)
    doc.saveas(path)
    return Path(path)
