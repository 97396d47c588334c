"""Plans drawn one layer per room (issue 34: a shopping-mall level of
JuPedSim, 'Raum_001' ... 'Raum_344' and 'Tueren' door lines; an Indian
house with both storeys side by side, 'BedRoom1', 'BedRoom1a', 'Kitchen'
...; an office traced over a scan on layers 'room' and 'hall'), each
written here with ezdxf: the rooms' outlines are the walls, the door lines
connect the rooms, and 'mapkit layers' says which rule decided."""

from __future__ import annotations

import json
from collections import Counter

import ezdxf
import pytest
from shapely.geometry import box

from cli_helpers import run
from mapkit.importers import load_scene
from mapkit.importers.dxf.room_layers import room_outline_layers, room_stem
from mapkit.shapes import polygon_parts


def _room(msp, layer: str, x0: float, y0: float, x1: float, y1: float, gaps=()):
    """A room's outline as LINEs on its own layer, left open at each gap
    ``(side, a, b)``: side 'w'/'e' (x0/x1, from y a to b) or 's'/'n'."""
    sides = {"s": ((x0, y0), (x1, y0)), "e": ((x1, y0), (x1, y1)), "n": ((x1, y1), (x0, y1)), "w": ((x0, y1), (x0, y0))}
    for side, (p, q) in sides.items():
        cuts = sorted((a, b) for s, a, b in gaps if s == side)
        along = 0 if side in "sn" else 1
        lo, hi = sorted((p[along], q[along]))
        points = [lo] + [v for a, b in cuts for v in (a, b)] + [hi]
        for a, b in zip(points[::2], points[1::2]):
            if side in "sn":
                msp.add_line((a, p[1]), (b, p[1]), dxfattribs={"layer": layer})
            else:
                msp.add_line((p[0], a), (p[0], b), dxfattribs={"layer": layer})


def _mall(path, units: int = 6):
    """Three 4 x 4 m rooms in a row, each on its layer 'Raum_00k' as lines,
    doors 1 m wide between them and into the first from outside as lines
    on 'Tueren' across the gaps their outlines leave, a 1.2 x 3 m escalator
    lane 'Raum_004' off the first room (a door line at each end), a 0.4 m pillar drawn
    on the first room's layer, a pocket 12 x 1 m that the three rooms'
    walls close off (no room of its own, no door), and a niche
    in the third room its own lines close off (no door)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = units
    msp = doc.modelspace()
    door = {"layer": "Tueren"}
    _room(msp, "Raum_001", 0, 0, 4, 4, [("w", 1.5, 2.5), ("e", 1.5, 2.5), ("s", 1, 2.2)])
    # An escalator lane off the first room: its side walls end square to the door lines at both its ends.
    msp.add_line((1, 0), (1, -3), dxfattribs={"layer": "Raum_004"})
    msp.add_line((2.2, 0), (2.2, -3), dxfattribs={"layer": "Raum_004"})
    msp.add_line((1, 0), (2.2, 0), dxfattribs=door)
    msp.add_line((1, -3), (2.2, -3), dxfattribs=door)
    _room(msp, "Raum_002", 4, 0, 8, 4, [("w", 1.5, 2.5), ("e", 1.5, 2.5)])
    _room(msp, "Raum_003", 8, 0, 12, 4, [("w", 1.5, 2.5)])
    msp.add_lwpolyline([(1.8, 2.8), (2.2, 2.8), (2.2, 3.2), (1.8, 3.2)], close=True, dxfattribs={"layer": "Raum_001"})
    # The pocket: north of the three rooms, closed by lines on each of their layers.
    msp.add_line((0, 4), (0, 5), dxfattribs={"layer": "Raum_001"})
    msp.add_line((0, 5), (4, 5), dxfattribs={"layer": "Raum_001"})
    msp.add_line((4, 5), (8, 5), dxfattribs={"layer": "Raum_002"})
    msp.add_line((8, 5), (12, 5), dxfattribs={"layer": "Raum_003"})
    msp.add_line((12, 5), (12, 4), dxfattribs={"layer": "Raum_003"})
    # A niche 1.2 m square the third room's own lines close off, with no door.
    msp.add_line((10.8, 4), (10.8, 2.8), dxfattribs={"layer": "Raum_003"})
    msp.add_line((10.8, 2.8), (12, 2.8), dxfattribs={"layer": "Raum_003"})
    for x in (0, 4, 8):
        msp.add_line((x, 1.5), (x, 2.5), dxfattribs=door)
    msp.add_text("Raum 1", dxfattribs={"layer": "Raum_001"}).set_placement((1, 1))
    doc.saveas(path)
    return path


def test_per_room_layers_are_the_walls_and_the_door_lines_connect_them(tmp_path):
    """Refused before ("no recognisable walls": 'Raum_*' named rooms, read as
    room fills); now the rooms' outlines are the walls, the five door lines
    five doors (the lane's two too, whose walls end square to them: no wall
    gap of a door leaf), the rooms one free space, and the free space inside
    the rooms only: not the pocket between the walls, not the pillar, not
    the niche no door leads into."""
    scene = load_scene(_mall(tmp_path / "mall.dxf"))
    assert [o.kind for o in scene.openings] == ["door"] * 5
    parts = polygon_parts(scene.free_space)
    assert len(parts) == 1
    assert scene.info["interior"] == "room outlines"
    # Three 16 m2 rooms and the 3.6 m2 lane less the pillar, shrunk by the
    # robot's 0.2 m: under 51.6 m2, nothing of the pocket.
    assert 30 < scene.free_space.area < 51.6 - 0.16
    assert not any("not in a wall gap" in w for w in scene.info["warnings"])
    assert scene.free_space.intersection(box(0, 4, 12, 5)).area == 0
    assert scene.free_space.intersection(box(1.8, 2.8, 2.2, 3.2)).area == 0
    assert scene.free_space.intersection(box(10.8, 2.8, 12, 4)).area == 0
    assert any("the rooms' outlines on 'Raum_001', 'Raum_002', 'Raum_003', 'Raum_004'" in w for w in scene.info["warnings"])


def test_mapkit_layers_says_the_per_room_rule(tmp_path, capsys):
    """'mapkit layers' names the rule that made the room layers walls."""
    code, out, err = run(capsys, "layers", _mall(tmp_path / "mall.dxf"), "--json")
    assert code == 0, err
    rows = {r["name"]: r for r in json.loads(out)["layers"]}
    assert rows["Raum_002"]["role"] == "walls"
    assert "one of 4 per-room layers 'Raum*'" in rows["Raum_002"]["why"]
    assert rows["Tueren"]["role"] == "doors"


def test_room_layers_named_as_walls_are_not_second_guessed(tmp_path):
    """--walls names the walls: the other room layers then stay what their
    names say (room fills)."""
    from mapkit.importers.dxf.layers import layer_counts, resolve_layer_roles
    from mapkit.options import BuildOptions

    doc = ezdxf.readfile(_mall(tmp_path / "mall.dxf"))
    roles, _, outlines = resolve_layer_roles(layer_counts(doc), BuildOptions(walls=["Raum_001"]))
    assert outlines == [] and roles["Raum_002"] == "floor" and roles["Raum_001"] == "walls"


def test_which_numbered_layers_are_rooms():
    """A stem and a running number make a room layer only for names that say
    no other role, three or more of them, traced as lines, outweighing the
    wall layers: door, generic and zone-polygon layers keep their roles."""
    assert room_stem("Raum_001") == "raum" and room_stem("BathRoom2a") == "bathroom"
    assert room_stem("Layer1") is None and room_stem("0-3") is None and room_stem("Kitchen") is None
    assert room_stem("F-0") is None  # a pen code of a framing plan (walldet_sample's 'F-0', 'F-4', 'F-8')
    lines = Counter({"LINE": 6})
    counts = {f"Raum_00{k}": lines for k in range(1, 4)} | {f"Door{k}": lines for k in range(1, 4)} \
        | {f"Layer{k}": lines for k in range(1, 4)} | {f"Zone{k}": Counter({"LWPOLYLINE": 1}) for k in range(1, 4)}
    roles = {"Door1": "doors", "Door2": "doors", "Door3": "doors"} | {f"Zone{k}": "floor" for k in range(1, 4)}
    decided = room_outline_layers(counts, roles, set(counts))
    assert sorted(decided) == ["Raum_001", "Raum_002", "Raum_003"]
    # Two numbered layers are not a drawing of rooms; a wall layer with more linework wins.
    assert room_outline_layers({k: lines for k in ("R_001", "R_002")}, {}, {"R_001", "R_002"}) == {}
    heavy = counts | {"A-WALL": Counter({"LINE": 100})}
    assert room_outline_layers(heavy, roles | {"A-WALL": "walls"}, set(counts)) == {}


def _storeys(path):
    """A house's two storeys side by side 20 m apart (inches, as the Indian
    house): one layer per room ('BedRoom1', 'BedRoom2', 'BedRoom1a', ...,
    'Kitchen'),
    door lines on 'Door3fD.Panel', and one short line on a layer named for
    a wall (a staircase wall), which made that line the only walls."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 1
    msp = doc.modelspace()
    m = 1 / 0.0254  # inches per metre
    for dx, suffix in ((0.0, ""), (20.0, "a")):
        x = dx * m
        _room(msp, f"BedRoom1{suffix}", x, 0, x + 4 * m, 4 * m, [("e", 1.5 * m, 2.4 * m), ("n", x + 2 * m, x + 2.9 * m)])
        _room(msp, f"BathRoom1{suffix}", x + 4 * m, 0, x + 6 * m, 4 * m, [("w", 1.5 * m, 2.4 * m)])
        _room(msp, f"BedRoom2{suffix}", x, 4 * m, x + 6 * m, 6 * m,
              [("s", x + 2 * m, x + 2.9 * m), ("e", 4.5 * m, 5.4 * m)])
        _room(msp, "Kitchen" if not suffix else "Kitchen_upper", x + 6 * m, 0, x + 9 * m, 6 * m,
              [("w", 4.5 * m, 5.4 * m)])
        msp.add_line((x + 4 * m, 1.5 * m), (x + 4 * m, 2.4 * m), dxfattribs={"layer": "Door3fD.Panel"})
        msp.add_line((x + 2 * m, 4 * m), (x + 2.9 * m, 4 * m), dxfattribs={"layer": "Door3fD.Panel"})
        msp.add_line((x + 6 * m, 4.5 * m), (x + 6 * m, 5.4 * m), dxfattribs={"layer": "Door3fD.Panel"})
    msp.add_line((-0.5 * m, 0), (-0.5 * m, 3 * m), dxfattribs={"layer": "Entrance_Staircase_wall"})
    doc.saveas(path)
    return path


def test_two_storeys_drawn_one_layer_per_room_are_two_plans(tmp_path):
    """Wrong before: the staircase wall's one line was the walls (the rooms
    read as fills): the real house built as that line's convex hull, this
    one refused for no free space; now the rooms'
    outlines are the walls, the sheet's two storeys two plans (the largest
    built, the other named), and the storey's rooms connect through its doors."""
    scene = load_scene(_storeys(tmp_path / "house.dxf"))
    warnings = scene.info["warnings"]
    assert any("the drawing holds 2 separate plans" in w for w in warnings), warnings
    assert not any("convex hull" in w for w in warnings)
    assert [o.kind for o in scene.openings] == ["door"] * 3
    assert len(polygon_parts(scene.free_space)) == 1
    # One storey's 54 m2, shrunk by the robot's radius: the other storey is not in it.
    assert 35 < scene.free_space.area < 54


def test_rooms_traced_on_space_layers_at_an_unknown_scale_name_the_units(tmp_path, capsys):
    """An office traced over a scan on layers 'room' and 'hall' and no wall
    layer, drawn in centimetres that say millimetres, was refused with "no
    recognisable walls"; its rooms' outlines are its walls, and the refusal
    names the --units that make it a building's size, in one line."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    for k in range(4):  # four 350 x 550 rooms along a 200 wide hall
        _room(msp, "room", 350 * k, 0, 350 * (k + 1), 550)
    _room(msp, "hall", 0, 550, 1400, 750)
    msp.add_line((100, 100), (100, 700), dxfattribs={"layer": "edge"})
    plan = tmp_path / "traced.dxf"
    doc.saveas(plan)
    code, _, err = run(capsys, "build", plan, "-o", tmp_path / "traced.lmap")
    errors = [ln for ln in err.splitlines() if ln.startswith("mapkit: error:")]
    assert code == 2 and len(errors) == 1, err
    assert "no recognisable walls" not in errors[0]
    assert "give --units cm" in errors[0]
    assert not (tmp_path / "traced.lmap").exists()
    code, out, err = run(capsys, "layers", plan, "--json")
    rows = {r["name"]: r for r in json.loads(out)["layers"]}
    assert rows["hall"]["role"] == "walls" and "no layer holds walls" in rows["hall"]["why"]
    assert rows["edge"]["role"] == "unknown"


def test_door_symbols_other_than_lines_are_left_whole():
    """Each straight door line of a per-room plan is a door of its own; a
    door drawn as a leaf and its swing stays one drawing (its strokes keep
    no group of their own)."""
    import numpy as np

    from mapkit.importers.dxf.room_layers import door_lines_apart
    from mapkit.importers.dxf.strokes import Stroke

    lines = [Stroke(np.array([[0.0, 0.0], [1.0, 0.0]]), layer="Tueren"), Stroke(np.array([[1.0, 0.0], [2.0, 0.0]]))]
    assert [s.group for s in door_lines_apart(lines, 7)] == [7, 8]
    swing = lines[:1] + [Stroke(np.array([[1.0, 0.0], [0.7, 0.7], [0.0, 1.0]]))]
    assert [s.group for s in door_lines_apart(swing, 7)] == [None, None]


@pytest.mark.parametrize("name", ["Kitchen", "DiningRoom", "hall", "Walkway", "Balcony1"])
def test_space_names(name):
    from mapkit.importers.dxf.room_layers import is_general_space_name, is_space_name

    assert is_space_name(name)
    assert not is_space_name("Parking") and not is_space_name("Boundary")
    # Alone, without a drawing of one layer per room, only general words make rooms' outlines.
    assert is_general_space_name("hall") and is_general_space_name("room")
    assert not is_general_space_name("Kitchen stuff")
