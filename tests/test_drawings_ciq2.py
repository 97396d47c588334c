"""Doors of a house plan drawn over the walls they open: the corpus's
ciq_building, plan #1 (``--walls DETAILS --units mm``).

Its door swings are drawn over walls left unbroken under them: a facade's
outer face drawn straight across a bay's French doors, a frame drawn as a
closed rectangle across a 0.1 m wall (the door hinged in a room's corner,
its leaf beside the wall there), the main entrance on a diagonal wall of
four parallel lines (its leaf opened flat along the wall beside it). Each
sealed the rooms it leads into; a swing's closed leaf now says where its
opening is (:mod:`mapkit.importers.dxf.closed_leaf`). The drawings are small
DXF files written here with ezdxf, in metres, everything on one layer.
"""

from __future__ import annotations

import math

import ezdxf
from shapely.geometry import Point, Polygon

from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.shapes import polygon_parts

LAYER = "WALLS"


def _write(path, polylines: list, lines: list, arcs: list, turn_deg: float = 0.0):
    """A DXF in metres on ``LAYER``: closed ``polylines`` (point lists),
    ``lines`` ((a, b) pairs) and ``arcs`` ((centre, radius, start, end)),
    all turned by ``turn_deg`` about the origin."""
    c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))

    def turn(p):
        return (c * p[0] - s * p[1], s * p[0] + c * p[1])

    doc = ezdxf.new("R2013", setup=False)
    doc.header["$INSUNITS"] = 6
    doc.layers.add(LAYER)
    msp = doc.modelspace()
    at = {"layer": LAYER}
    for pts in polylines:
        msp.add_lwpolyline([turn(p) for p in pts], close=True, dxfattribs=at)
    for a, b in lines:
        msp.add_line(turn(a), turn(b), dxfattribs=at)
    for centre, radius, start, end in arcs:
        msp.add_arc(turn(centre), radius, start + turn_deg, end + turn_deg, dxfattribs=at)
    doc.saveas(path)
    return path


def _box(x0, y0, x1, y1):
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def _scene(path):
    return load_scene(path, BuildOptions(walls=[LAYER]))


def _turned(p, turn_deg: float) -> Point:
    c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    return Point(c * p[0] - s * p[1], s * p[0] + c * p[1])


def test_french_doors_across_a_facade_line_open_onto_the_bay(tmp_path):
    """A room 6 x 4 m whose bottom wall is a double line (y 0.05 to 0.15)
    with a 0.9 m gap, its outer face (y 0) drawn straight across the gap;
    below it a bay whose slanted sides start beside the jambs. The French
    doors' leaves swing out across the face line into the bay: before, the
    line sealed the bay off (two parts, no door found; the bay's side by a
    leaf was taken for the wall the door is in)."""
    lines = [((-0.15, 0), (6.15, 0)), ((0, 0.05), (2.55, 0.05)), ((3.45, 0.05), (6, 0.05)),
             ((0, 0.15), (2.55, 0.15)), ((3.45, 0.15), (6, 0.15)),
             ((2.5, 0), (2, -0.5)), ((2, -0.5), (2, -1.2)), ((2, -1.2), (4, -1.2)), ((4, -1.2), (4, -0.5)),
             ((4, -0.5), (3.5, 0)),
             ((2.55, 0.15), (2.55, -0.31)), ((3.45, 0.15), (3.45, -0.31))]
    # The room's other walls: a double line 0.15 m thick, meeting the bottom wall's lines.
    lines += _open_outline([(-0.15, 0), (-0.15, 4.3), (6.15, 4.3), (6.15, 0)])
    lines += _open_outline([(0, 0.05), (0, 4.15), (6, 4.15), (6, 0.05)])
    # The leaves 0.46 m, their arcs meeting tip to tip at the middle, 12 degrees short of the wall.
    tip = math.degrees(math.acos(0.45 / 0.46))
    arcs = [((2.55, 0.15), 0.46, 270, 360 - tip), ((3.45, 0.15), 0.46, 180 + tip, 270)]
    path = _write(tmp_path / "bay.dxf", [], lines, arcs)
    scene = _scene(path)
    parts = polygon_parts(scene.free_space)
    assert scene.info["counts"]["doors"] == 1
    assert len(parts) == 1
    assert parts[0].contains(Point(3.0, -0.7))  # the bay, through the doors
    assert parts[0].contains(Point(3.0, 2.0))


def _open_outline(pts):
    return [(a, b) for a, b in zip(pts[:-1], pts[1:])]


def _two_rooms(band: list[float], door_lines: list, door_arcs: list, stub: list):
    """Two rooms 4 x 3 m, one below y 0 and one above the wall between them,
    whose lines (at each y of ``band``) run unbroken from wall to wall; the
    outer walls a double line 0.2 m thick; ``stub``: a short wall's closed
    outline beside the door; the door's ``door_lines`` and ``door_arcs``."""
    top = band[-1] + 3.0
    polylines = [_box(-0.2, -3.2, 4.2, top + 0.2), _box(0, -3, 4, top), stub]
    lines = [((0, y), (4, y)) for y in band] + door_lines
    return polylines, lines, door_arcs


def test_a_swing_over_a_frame_rectangle_in_a_rooms_corner_opens_it(tmp_path):
    """A 0.1 m wall between two rooms, its doorway closed by the frame (the
    wall's two lines run across it); the door hinged on the wall's centre
    line in the corner a short wall makes, its open leaf 5 cm beside that
    wall. Before, the short wall beside the leaf was taken for the wall the
    door is in: no opening, the rooms apart."""
    stub = _box(0.8, 0.1, 1.0, 1.5)
    polylines, lines, arcs = _two_rooms([0.0, 0.1], [((1.05, 0.05), (1.05, 0.85))], [((1.05, 0.05), 0.8, 0, 90)],
                                        stub)
    scene = _scene(_write(tmp_path / "frame.dxf", polylines, lines, arcs))
    parts = polygon_parts(scene.free_space)
    assert scene.info["counts"]["doors"] == 1
    assert len(parts) == 1
    assert parts[0].contains(Point(2.0, -1.5)) and parts[0].contains(Point(2.0, 1.5))


def test_an_entrance_on_a_diagonal_wall_of_parallel_lines_opens_it(tmp_path):
    """The ciq main entrance: a wall 0.2 m thick drawn as four parallel
    lines unbroken across the doorway, at 45 degrees, the door 1 m wide
    hinged inside the wall, its leaf opened flat along the short wall beside
    it. Before, that short wall was taken for the wall the door is in."""
    stub = _box(0.8, -1.6, 1.0, 0.0)
    band = [0.0, 0.05, 0.15, 0.2]
    polylines, lines, arcs = _two_rooms(band, [((1.05, 0.1), (1.05, -0.9))], [((1.05, 0.1), 1.0, 270, 360)], stub)
    scene = _scene(_write(tmp_path / "entrance.dxf", polylines, lines, arcs, turn_deg=45.0))
    parts = polygon_parts(scene.free_space)
    assert scene.info["counts"]["doors"] == 1
    assert len(parts) == 1
    assert parts[0].contains(_turned((2.5, -1.5), 45.0)) and parts[0].contains(_turned((2.5, 1.5), 45.0))


def test_a_swing_beside_a_wall_cuts_nothing(tmp_path):
    """A door drawn in a room, its closed leaf 0.3 m off the wall (a
    cupboard's door, not a doorway): the wall stays whole, the room one."""
    polylines, lines, arcs = _two_rooms([0.0, 0.1], [((1.05, 0.4), (1.05, 1.2))], [((1.05, 0.4), 0.8, 0, 90)],
                                        _box(0.8, 0.1, 1.0, 1.5))
    scene = _scene(_write(tmp_path / "beside.dxf", polylines, lines, arcs))
    assert scene.info["counts"]["doors"] == 0
    assert not any(p.contains(Point(2.0, -1.5)) and p.contains(Point(2.0, 1.5))
                   for p in polygon_parts(scene.free_space))


def test_a_wc_door_opens_where_its_leaf_closes_not_beside_the_bowl(tmp_path):
    """A WC 1 x 2 m off a hall, the wall between 0.1 m thick, its WC face
    drawn straight across the doorway; the door hinged at the doorway's top,
    its leaf open along the WC's top wall, its arc passing by the bowl.
    Before, the gap between the doorway's jamb and the bowl was taken for
    the door's: the WC stayed a sliver of free space of its own."""
    lines = [((0, -2), (0, -0.75)), ((0, -0.75), (0.1, -0.75)), ((0.1, -2), (0.1, 0)),  # the wall, its doorway
             ((0, 0), (1.1, 0)), ((0, 0.1), (1.1, 0.1)), ((0, 0), (0, 0.1)),  # the WC's top wall
             ((0.05, -0.075), (0.725, -0.075))]  # the leaf
    lines += _open_outline([(-3, -2), (1.1, -2), (1.1, 1), (-3, 1), (-3, -2)])
    lines += _open_outline([(-3.2, -2.2), (1.3, -2.2), (1.3, 1.2), (-3.2, 1.2), (-3.2, -2.2)])
    polylines = [_box(0.6, -0.95, 1.05, -0.45)]  # the bowl
    arcs = [((0.05, -0.075), 0.675, 270, 360)]
    scene = _scene(_write(tmp_path / "wc.dxf", polylines, lines, arcs))
    parts = polygon_parts(scene.free_space)
    assert scene.info["counts"]["doors"] == 1
    assert len(parts) == 1
    assert parts[0].contains(Point(0.35, -1.5)) and parts[0].contains(Point(-1.5, 0))


def _hall_with_box(box_lines: list):
    """A plan 6 x 4 m (double-line outer walls): a room 2 m wide off a hall,
    its door a swing in the single-line wall between them; in the hall's
    corner, against the outer walls, ``box_lines`` (single lines)."""
    lines = [((2, 0), (2, 1)), ((2, 1.9), (2, 4)), ((2, 1), (2.9, 1))] + list(box_lines)  # the wall, the door's leaf
    return [_box(-0.2, -0.2, 6.2, 4.2), _box(0, 0, 6, 4)], lines, [((2, 1), 0.9, 0, 90)]


#: A lift's box in the hall's corner, 1.9 x 1.83 m, its right side a little
#: slanted (as drawn), and its X: four strokes from the corners stopping
#: 0.2 to 0.3 m short of the centre, unevenly.
LIFT_BOX = [((4.059, 2.17), (5.958, 2.17)), ((4.059, 2.17), (4.059, 4.0)), ((5.958, 2.17), (6.0, 4.0))]
LIFT_X = [((4.059, 4.0), (4.836, 3.251)), ((6.0, 4.0), (5.211, 3.256)), ((4.059, 2.17), (4.934, 2.995)),
          ((5.127, 2.971), (5.958, 2.17))]


def test_an_x_across_a_box_is_a_mark_not_walls(tmp_path):
    """A lift marked by an X. Before, the X cut its box into triangles of
    free space, joined to each other through the gaps between the strokes'
    ends at the centre as through doorways: four parts. Now the box is one
    space no door leads into, left out."""
    polylines, lines, arcs = _hall_with_box(LIFT_BOX + LIFT_X)
    scene = _scene(_write(tmp_path / "lift.dxf", polylines, lines, arcs))
    parts = polygon_parts(scene.free_space)
    assert scene.info["counts"]["doors"] == 1
    assert len(parts) == 1
    assert not scene.free_space.intersects(Polygon([(4.06, 2.17), (5.96, 2.17), (6.0, 4.0), (4.06, 4.0)]))


def test_walls_crossing_in_a_plus_stay_walls(tmp_path):
    """Two walls crossing in a box's middle, one drawn in two strokes with a
    gap where they cross (as a plan's walls are), each ending on a vertex
    of the walls around it: they meet those square or run on in line, as
    walls do, not at a slant as a box's diagonals: walls, not a mark."""
    box = [((4, 2), (5, 2)), ((5, 2), (6, 2)), ((4, 2), (4, 3)), ((4, 3), (4, 4)),
           ((4, 3), (6, 3)), ((5, 2), (5, 2.9)), ((5, 3.1), (5, 4)), ((6, 2), (6, 3))]
    polylines, lines, arcs = _hall_with_box(box)
    # The hall's walls, with a vertex at each wall's end.
    polylines[1] = [(0, 0), (6, 0), (6, 2), (6, 3), (6, 4), (5, 4), (0, 4)]
    scene = _scene(_write(tmp_path / "plus.dxf", polylines, lines, arcs))
    assert not any("marks, not walls" in w for w in scene.info["warnings"])
    assert scene.walls.distance(Point(5.0, 2.5)) < 0.06 and scene.walls.distance(Point(4.5, 3.0)) < 0.06


def test_a_swing_between_glass_panes_is_found_in_their_gap(tmp_path):
    """A door swing between two glass panes (a glass front): its gap is
    the panes', and no wall is near where its leaf closes. Checking
    whether a wall crosses there must not fail for want of walls (it did:
    an internal error)."""
    doc = ezdxf.new("R2013", setup=False)
    doc.header["$INSUNITS"] = 6
    for name in (LAYER, "GLASS"):
        doc.layers.add(name)
    msp = doc.modelspace()
    walls, glass = {"layer": LAYER}, {"layer": "GLASS"}
    msp.add_lwpolyline([(0, 0), (0, 4), (6, 4), (6, 0)], dxfattribs=walls)
    msp.add_lwpolyline([(-0.2, 0), (-0.2, 4.2), (6.2, 4.2), (6.2, 0)], dxfattribs=walls)
    msp.add_line((-0.2, 0), (0, 0), dxfattribs=walls)
    msp.add_line((6, 0), (6.2, 0), dxfattribs=walls)
    msp.add_line((0, 0), (2.5, 0), dxfattribs=glass)
    msp.add_line((3.4, 0), (6, 0), dxfattribs=glass)
    msp.add_line((2.5, 0), (2.5, 0.9), dxfattribs=walls)  # the leaf, open into the room
    msp.add_arc((2.5, 0), 0.9, 0, 90, dxfattribs=walls)
    path = tmp_path / "glass.dxf"
    doc.saveas(path)
    scene = load_scene(path, BuildOptions(walls=[LAYER], windows=["GLASS"]))
    assert scene.info["counts"]["doors"] == 1
    assert len(polygon_parts(scene.free_space)) == 1
