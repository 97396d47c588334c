"""Failures the Chinese college floors of the corpus (daoshi_f1, daoshi_f3
of docs/benchmarks/drawings.tsv) showed, each reproduced in a small drawing
written here."""

from __future__ import annotations

import ezdxf
import numpy as np
import shapely

from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.shapes import polygon_parts


def _box(msp, x0, y0, x1, y1, layer):
    msp.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True, dxfattribs={"layer": layer})


def _swing(msp, hinge, width, layer="门线"):
    """A door swing drawn upwards from ``hinge`` on a horizontal wall: leaf and quarter arc (mm)."""
    x, y = hinge
    msp.add_line((x, y), (x, y + width), dxfattribs={"layer": layer})
    msp.add_arc((x, y), width, 0, 90, dxfattribs={"layer": layer})


def _floor_with_shaft_and_light_well(path, door: bool = True, loose_swing: bool = False):
    """Two rooms (mm, layers named as the college's: 墙线 wall lines, 门线
    doors, 窗线 windows) side by side, 6 x 5 m each, walls 200 mm thick drawn
    as double lines; between them a pipe shaft 0.8 x 1.5 m walled in on all
    sides; at the back a light well 3 x 2 m walled in, its window to room A
    drawn as glass lines in a gap of its wall. Room A has a door to room B
    (``door``) and one to the outside in its front wall; without it, with
    ``loose_swing``, a swing is drawn against the walled-up partition's face
    in room B (a door drawing no gap is found for)."""
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    w = "墙线"
    # The outer outline 0..12400 x 0..7400 and its inner face, with the front door's gap in A (x 1000..1900).
    msp.add_lwpolyline([(1900, 0), (12400, 0), (12400, 7400), (0, 7400), (0, 0), (1000, 0)], dxfattribs={"layer": w})
    msp.add_lwpolyline([(1900, 200), (12200, 200), (12200, 7200), (200, 7200), (200, 200), (1000, 200)],
                       dxfattribs={"layer": w})
    msp.add_line((1000, 0), (1000, 200), dxfattribs={"layer": w})
    msp.add_line((1900, 0), (1900, 200), dxfattribs={"layer": w})
    _swing(msp, (1000, 200), 900)
    # The partition between A (x < 6200) and B (x > 6400), with its door gap y 1000..1900.
    msp.add_lwpolyline([(6200, 1000), (6200, 200)], dxfattribs={"layer": w})
    msp.add_lwpolyline([(6400, 200), (6400, 1000)], dxfattribs={"layer": w})
    msp.add_line((6200, 1000), (6400, 1000), dxfattribs={"layer": w})
    msp.add_lwpolyline([(6200, 1900), (6200, 7200)], dxfattribs={"layer": w})
    msp.add_lwpolyline([(6400, 1900), (6400, 7200)], dxfattribs={"layer": w})
    msp.add_line((6200, 1900), (6400, 1900), dxfattribs={"layer": w})
    if door:
        msp.add_line((6400, 1000), (7300, 1000), dxfattribs={"layer": "门线"})
        msp.add_arc((6400, 1000), 900, 0, 90, dxfattribs={"layer": "门线"})
    else:  # the gap walled up
        msp.add_line((6200, 1000), (6200, 1900), dxfattribs={"layer": w})
        msp.add_line((6400, 1000), (6400, 1900), dxfattribs={"layer": w})
        if loose_swing:
            msp.add_line((6420, 1000), (7320, 1000), dxfattribs={"layer": "门线"})
            msp.add_arc((6420, 1000), 900, 0, 90, dxfattribs={"layer": "门线"})
    # A pipe shaft in room B's corner: 0.8 x 1.5 m inside, walls 100 mm, no door.
    _box(msp, 6400, 5500, 7500, 7200, w)
    _box(msp, 6500, 5600, 7400, 7100, w)
    # A light well at the back of room A: 3 x 2 m inside walls 200 mm, a window to A (x 2000..3000).
    msp.add_lwpolyline([(3000, 4800), (4800, 4800), (4800, 7200)], dxfattribs={"layer": w})
    msp.add_lwpolyline([(3000, 5000), (4600, 5000), (4600, 7200)], dxfattribs={"layer": w})
    msp.add_lwpolyline([(2000, 4800), (1400, 4800), (1400, 7200)], dxfattribs={"layer": w})
    msp.add_lwpolyline([(2000, 5000), (1600, 5000), (1600, 7200)], dxfattribs={"layer": w})
    msp.add_line((2000, 4800), (2000, 5000), dxfattribs={"layer": w})
    msp.add_line((3000, 4800), (3000, 5000), dxfattribs={"layer": w})
    for y in (4800, 4900, 5000):
        msp.add_line((2000, y), (3000, y), dxfattribs={"layer": "窗线"})
    doc.saveas(path)
    return path


def _parts_and_warnings(path):
    # What the reconstruction keeps, whatever the self-check makes of it (a
    # room walled up leaves most of this small floor out: it is refused
    # without --accept-inconsistent, tests/test_self_check.py).
    scene = load_scene(path, BuildOptions(accept_inconsistent=True))
    return polygon_parts(scene.free_space), scene.info.get("warnings", [])


def test_shafts_and_light_wells_no_door_leads_into_are_not_free_space(tmp_path):
    """daoshi_f3's free space was in 60 parts although its rooms connect
    through their doors: the walls also enclose pipe shafts, light wells,
    a roof terrace and the panels of a glazed roof, each a part of its own.
    No door or doorway leads into them: they are left out, with a warning."""
    parts, warnings = _parts_and_warnings(_floor_with_shaft_and_light_well(tmp_path / "floor.dxf"))
    assert len(parts) == 1
    room_a, room_b = shapely.Point(3, 2), shapely.Point(9, 3)
    assert parts[0].contains(room_a) and parts[0].contains(room_b)
    for void in (shapely.Point(6.95, 6.35), shapely.Point(3.1, 6.1)):  # the shaft, the light well
        assert not parts[0].buffer(0.3).contains(void)
    assert any("2 enclosed space(s) that no door or doorway leads into" in w for w in warnings), warnings


def test_a_room_entered_only_through_a_door_to_the_outside_is_kept(tmp_path):
    """Only spaces no door touches are left out: with the inner door walled
    up, room B has no door at all and is left out, room A (its door opens to
    the outside) stays."""
    parts, warnings = _parts_and_warnings(_floor_with_shaft_and_light_well(tmp_path / "floor.dxf", door=False))
    assert len(parts) == 1
    assert parts[0].contains(shapely.Point(3, 2)) and not parts[0].contains(shapely.Point(9, 3))
    assert any("3 enclosed space(s)" in w for w in warnings), warnings


def test_a_room_with_a_door_drawing_whose_gap_was_not_found_is_kept(tmp_path):
    """A door drawn where no gap is found (against a wall's face) still
    marks its room as entered: the room stays, a part of its own, and the
    lost door is warned about (the missing door shows in the count)."""
    path = _floor_with_shaft_and_light_well(tmp_path / "floor.dxf", door=False, loose_swing=True)
    parts, warnings = _parts_and_warnings(path)
    assert len(parts) == 2
    assert any(p.contains(shapely.Point(9, 3)) for p in parts)
    assert any("not in a wall gap" in w for w in warnings), warnings
    assert any("2 enclosed space(s)" in w for w in warnings), warnings


def test_a_plan_without_doors_keeps_every_part(tmp_path):
    """With no door found, no entry can be told from none: every room stays."""
    path = tmp_path / "rooms.dxf"
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    for x in (0.0, 6.0):
        _box(msp, x, 0, x + 5, 4, "墙线")
        _box(msp, x + 0.2, 0.2, x + 4.8, 3.8, "墙线")
    doc.saveas(path)
    parts, warnings = _parts_and_warnings(path)
    assert len(parts) == 2
    assert not any("no door or doorway" in w for w in warnings)
    assert np.isclose(sum(p.area for p in parts), 2 * 4.2 * 3.2, rtol=0.2)


def _row_of_rooms(path, stray: bool):
    """Three rooms 4 x 4 m in a row (m), walls 0.2 m as double lines, each
    with a door gap 0.9 m wide in its front wall and a swing drawn in it on
    '门线'; with ``stray``, a 20 m polyline on the door layer '门窗墙' (the
    college floor's dimension chain) runs along the front walls through
    the swings of every door."""
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    w = "墙线"
    for k in range(3):
        x = 4.2 * k
        # Outer and inner faces, the front wall broken by the gap x+1.5 .. x+2.4.
        msp.add_lwpolyline([(x + 2.4, 0), (x + 4.4, 0), (x + 4.4, 4.4), (x, 4.4), (x, 0), (x + 1.5, 0)],
                           dxfattribs={"layer": w})
        msp.add_lwpolyline([(x + 2.4, 0.2), (x + 4.2, 0.2), (x + 4.2, 4.2), (x + 0.2, 4.2), (x + 0.2, 0.2),
                            (x + 1.5, 0.2)], dxfattribs={"layer": w})
        msp.add_line((x + 1.5, 0), (x + 1.5, 0.2), dxfattribs={"layer": w})
        msp.add_line((x + 2.4, 0), (x + 2.4, 0.2), dxfattribs={"layer": w})
        msp.add_line((x + 1.5, 0.2), (x + 1.5, 1.1), dxfattribs={"layer": "门线"})
        msp.add_arc((x + 1.5, 0.2), 0.9, 0, 90, dxfattribs={"layer": "门线"})
    # A corridor in front of them, closed at its ends and along its front.
    msp.add_lwpolyline([(0, 0), (0, -2.2), (12.8, -2.2), (12.8, 0)], dxfattribs={"layer": w})
    msp.add_lwpolyline([(0.2, 0), (0.2, -2.0), (12.6, -2.0), (12.6, 0)], dxfattribs={"layer": w})
    if stray:
        msp.add_lwpolyline([(-1, 0.5), (13.8, 0.5), (13.8, 6), (-1, 6)], dxfattribs={"layer": "门窗墙"})
    doc.saveas(path)
    return path


def test_a_long_line_on_a_door_layer_does_not_glue_the_doors_together(tmp_path):
    """daoshi_f1 holds a 122 m polyline on '门窗墙' (a door-layer name: doors,
    windows, walls): read as part of the door drawings, it joined every door
    it passed into one drawing, and 5 of 82 doors were lost. A stroke longer
    than any door drawing is left out of the doors, with a warning."""
    plain = load_scene(_row_of_rooms(tmp_path / "plain.dxf", stray=False), BuildOptions())
    scene = load_scene(_row_of_rooms(tmp_path / "stray.dxf", stray=True), BuildOptions())
    assert sum(o.kind == "door" for o in plain.openings) == 3
    assert sum(o.kind == "door" for o in scene.openings) == 3
    assert len(polygon_parts(scene.free_space)) == 1
    assert any("span more than a door drawing" in w and "门窗墙" in w for w in scene.info["warnings"])


def test_dimensions_on_a_door_layer_are_not_measured_for_the_plan_extent(tmp_path, monkeypatch):
    """daoshi_f1 keeps 325 dimensions on '门窗墙', a layer whose name makes
    it a door layer: the plan's extent took ezdxf's bounding box of each
    (its whole rendered block, 3 s of the import) although dimensions are
    never built. Only entities that are built are measured, and a LINE's box
    is its end points."""
    import mapkit.importers.dxf as dxf_importer

    path = _row_of_rooms(tmp_path / "dims.dxf", stray=False)
    doc = ezdxf.readfile(path)
    msp = doc.modelspace()
    for k in range(5):
        msp.add_linear_dim(base=(0, -3 - k), p1=(0, 0), p2=(4.4 + k, 0), dxfattribs={"layer": "门窗墙"}).render()
    doc.saveas(path)
    measured = []
    real = dxf_importer.bbox.extents

    def counting(entities, *args, **kwargs):
        measured.extend(e.dxftype() for e in entities)
        return real(entities, *args, **kwargs)

    monkeypatch.setattr(dxf_importer.bbox, "extents", counting)
    drawing, info = dxf_importer.load_drawing(path, BuildOptions())
    assert "DIMENSION" not in measured and "LINE" not in measured
    assert "ARC" in measured and "LWPOLYLINE" in measured
    assert drawing.role("doors") and info["units"] == "m"
