"""Failures that real drawings made by strangers showed
(``tools/bench_drawings.py`` on the corpus of docs/benchmarks/drawings.md),
each reproduced in a small drawing these tests write."""

from __future__ import annotations

import json
from pathlib import Path

import ezdxf
import numpy as np
import pytest
import shapely
from cli_helpers import assert_one_line_error, run
from shapely import wkt

from linemap.lmap import load_map
from mapkit.importers.dxf.layer_roles import guess_role
from mapkit.importers.dxf.openings import _clipped

FLAT = Path(__file__).resolve().parent.parent / "maps" / "flat.dxf"


def _room(path, layer: str = "A-WALL", version: str = "R2013"):
    """A 5 x 4 m room of double-line walls 0.2 m thick on ``layer``."""
    doc = ezdxf.new(version)
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (5, 0), (5, 4), (0, 4)], close=True, dxfattribs={"layer": layer})
    msp.add_lwpolyline([(0.2, 0.2), (4.8, 0.2), (4.8, 3.8), (0.2, 3.8)], close=True, dxfattribs={"layer": layer})
    doc.saveas(path)
    return path


def test_a_model_space_layout_of_another_name_is_read(tmp_path, capsys):
    """An AutoCAD 2013 file written by other software names its model-space
    layout 'Default' (depthmapX's gallery.dxf); ezdxf's modelspace() then
    raised KeyError: 'MODEL', a traceback. Its *Model_Space block holds the
    drawing."""
    plain = _room(tmp_path / "plain.dxf")
    renamed = tmp_path / "renamed.dxf"
    renamed.write_text(plain.read_text().replace("\nModel\n", "\nDefault\n"))
    assert "\nModel\n" not in renamed.read_text()
    code, out, err = run(capsys, "build", renamed, "-o", tmp_path / "out.lmap")
    assert code == 0, err
    assert "Traceback" not in err and (tmp_path / "out.lmap").exists()


def test_a_wall_sliver_that_geos_rectangle_clip_refuses_is_clipped():
    """Single-line walls on one layer per room (JuPedSim's shopping mall)
    left a spike-shaped wall part on which GEOS's rectangle clip raised
    'Invalid number of points in LinearRing found 3' from inside the door
    search; the general intersection gives the same cut."""
    sliver = wkt.loads(
        "POLYGON ((400 703.4999999999999, 405.48584809268175 703.508050435386, 405.48584809268186 716.9691585455412, "
        "405.48584809268186 703.508050435386, 405.48584809268186 701.37597759, 405.48584809268175 703.5080504353859, "
        "400 703.4999999999999))")
    box = (392.84082582051, 716.9203400091477, 417.94156838924243, 750.2255208832047)
    cut = _clipped(sliver, box)
    assert cut.area == shapely.box(*box).intersection(sliver).area


#: The example flat's layers named as a Chinese, a Russian, a Japanese and
#: a Korean drawing name them (the Chinese college floors of the corpus:
#: 墙线 wall lines, 柱子 columns, 门线 door lines, 窗线 window lines).
FOREIGN_LAYERS = {
    "chinese": {"A-WALL": "墙线", "A-COLS": "柱子", "A-DOOR": "门线", "A-GLAZ": "窗线", "A-ANNO": "标注",
                "A-FURN": "家具", "A-FURN-OVHD": "家具2"},
    "russian": {"A-WALL": "Стены", "A-COLS": "Колонны", "A-DOOR": "Двери", "A-GLAZ": "Окна", "A-ANNO": "Размеры",
                "A-FURN": "Мебель", "A-FURN-OVHD": "Мебель-2"},
    "japanese": {"A-WALL": "壁", "A-COLS": "柱", "A-DOOR": "扉", "A-GLAZ": "窓", "A-ANNO": "寸法",
                 "A-FURN": "家具", "A-FURN-OVHD": "家具2"},
    "korean": {"A-WALL": "벽", "A-COLS": "기둥", "A-DOOR": "문", "A-GLAZ": "창", "A-ANNO": "치수",
               "A-FURN": "가구", "A-FURN-OVHD": "가구2"},
}


@pytest.mark.slow
@pytest.mark.parametrize("language", sorted(FOREIGN_LAYERS))
def test_layer_names_in_other_languages_build_as_the_english_ones(tmp_path, capsys, language):
    """The flat drawn with its layers named in another language builds with
    defaults into the same segments as with its AIA names (before: refused,
    'no recognisable walls')."""
    names = FOREIGN_LAYERS[language]
    doc = ezdxf.readfile(FLAT)
    for old, new in names.items():
        doc.layers.add(new)
        for e in doc.modelspace():
            if e.dxf.get("layer") == old:
                e.dxf.layer = new
    foreign = tmp_path / f"flat_{language}.dxf"
    doc.saveas(foreign)
    code, _, err = run(capsys, "build", foreign, "-o", tmp_path / "foreign.lmap", "-q")
    assert code == 0, err
    # The English one is the committed example map (test_build_real checks it is flat.dxf's build).
    a, b = load_map(tmp_path / "foreign.lmap"), load_map(FLAT.with_suffix(".lmap"))
    assert np.array_equal(a.segments, b.segments) and np.array_equal(a.kinds, b.kinds)


@pytest.mark.parametrize("layer,role", [
    ("墙线", "walls"), ("墙体", "walls"), ("柱子", "walls"), ("门线", "doors"), ("窗线", "windows"), ("窗户", "windows"),
    ("幕墙", "windows"), ("门墙窗标注", "ignore"), ("使用面积线", "ignore"), ("轴线", "ignore"), ("填充", "ignore"),
    ("Стены", "walls"), ("Перегородки", "walls"), ("Двери", "doors"), ("Окна", "windows"), ("Пол", "floor"),
    ("Полки", None), ("Оси", "ignore"), ("壁", "walls"), ("窓", "windows"), ("ドア", "doors"), ("寸法", "ignore"),
    ("벽", "walls"), ("문", "doors"), ("문자", "ignore"), ("창호", "windows"), ("Hatches", "ignore"), ("Luft", "ignore"),
    ("Muren", "walls"), ("Wanden", "walls"), ("Deuren", "doors"), ("Ramen", "windows"), ("Paredes", "walls"),
    ("Janelas", "windows"), ("Finestre", "windows"), ("Pareti", "walls"), ("Fenêtres", "windows"), ("Türen", "doors"),
])
def test_layer_words_of_many_languages(layer, role):
    assert guess_role(layer) == role


def _translated(plan, by_m, path):
    """``plan`` (the flat, drawn in millimetres) moved by ``by_m`` (x, y) metres, written to ``path``."""
    doc = ezdxf.readfile(plan)
    assert doc.header["$INSUNITS"] == 4
    for e in doc.modelspace():
        try:
            e.translate(by_m[0] * 1000, by_m[1] * 1000, 0.0)
        except (NotImplementedError, AttributeError, TypeError):  # dimensions and texts: ignored layers anyway
            pass
    doc.saveas(path)
    return path


@pytest.mark.slow
def test_a_georeferenced_drawing_is_moved_to_a_local_origin(tmp_path, capsys):
    """A facility-management plan 1758 km from its file's origin (a national
    grid) was refused ('coordinates exceed the format's range'); it builds
    in a local frame, the offset kept in the map, shown by 'mapkit info' and
    added back by 'mapkit export --drawing-coordinates'."""
    far = np.array([1_758_000.0, 512_000.0])  # metres
    geo_path = _translated(FLAT, far, tmp_path / "georeferenced.dxf")
    code, _, err = run(capsys, "build", geo_path, "-o", tmp_path / "geo.lmap", "-q")
    assert code == 0, err
    assert "1831 km from its origin (georeferenced)" in err
    geo = load_map(tmp_path / "geo.lmap")
    offset = np.array(geo.meta["origin_offset_m"])
    assert np.array_equal(offset, [1758000.0, 511999.0])  # the building's lower-left corner, whole metres
    # The same building drawn near the origin in the same local frame gives the same map.
    local_path = _translated(FLAT, far - offset, tmp_path / "local.dxf")
    code, _, err = run(capsys, "build", local_path, "-o", tmp_path / "local.lmap", "-q")
    assert code == 0 and "georeferenced" not in err, err
    local = load_map(tmp_path / "local.lmap")
    # The round trip through 1.8e9 mm leaves coordinates a micrometre apart,
    # which may tip where a wall edge is split or a quadtree cell divides.
    same = {tuple(np.round(s, 3).ravel()) for s in geo.segments} & {tuple(np.round(s, 3).ravel()) for s in local.segments}
    assert len(same) >= 0.98 * len(local.segments)
    assert abs(geo.n_regions - local.n_regions) <= 0.02 * local.n_regions

    code, out, _ = run(capsys, "info", tmp_path / "geo.lmap")
    assert code == 0 and f"the drawing's ({offset[0]:.3f}, {offset[1]:.3f}) m (georeferenced" in out
    code, _, err = run(capsys, "export", tmp_path / "geo.lmap", "--geojson", tmp_path / "geo.geojson",
                       "--drawing-coordinates")
    assert code == 0, err
    lines = [f for f in json.loads((tmp_path / "geo.geojson").read_text())["features"]
             if f["geometry"]["type"] == "LineString"]
    assert np.allclose(np.array(lines[0]["geometry"]["coordinates"])[:, :2], geo.segments[0, :, :2] + offset)


def _two_rooms(path, door: str):
    """Two 4 x 4 m rooms side by side, their shared wall unbroken, with one
    door drawn over it as ``door`` says: "swing" (single-line walls and the
    door's arc and leaf, all on layer 0, as the Hal9k hackerspace's plan,
    beside a furniture layer) or "rectangle" (double-line walls on EM_WALL,
    the door a rectangle on EM_DOOR across the wall, as the Vietnamese
    apartment cleaned for EnergyPlus)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    if door == "swing":
        wall = {"layer": "0"}
        msp.add_lwpolyline([(0, 0), (8, 0), (8, 4), (0, 4)], close=True, dxfattribs=wall)
        msp.add_line((4, 0), (4, 4), dxfattribs=wall)
        # Hinge at (4, 1); the leaf open square into the right room; the arc from its tip back to the wall.
        msp.add_line((4, 1), (4.9, 1), dxfattribs=wall)
        msp.add_arc((4, 1), 0.9, 0, 90, dxfattribs=wall)
        msp.add_lwpolyline([(1, 1), (2, 1), (2, 2), (1, 2)], close=True, dxfattribs={"layer": "Furniture"})
    else:
        wall = {"layer": "EM_WALL"}
        for x0, x1 in ((0, 4.1), (3.9, 8)):  # each room's outline, 0.2 m walls, shared at x 3.9-4.1
            msp.add_lwpolyline([(x0, 0), (x1, 0), (x1, 4), (x0, 4)], close=True, dxfattribs=wall)
            msp.add_lwpolyline([(x0 + 0.2, 0.2), (x1 - 0.2, 0.2), (x1 - 0.2, 3.8), (x0 + 0.2, 3.8)], close=True,
                               dxfattribs=wall)
        msp.add_lwpolyline([(3.9, 1), (4.1, 1), (4.1, 1.9), (3.9, 1.9)], close=True, dxfattribs={"layer": "EM_DOOR"})
    doc.saveas(path)
    return path


@pytest.mark.parametrize("door", ["swing", "rectangle"])
def test_a_door_drawn_over_an_unbroken_wall_cuts_its_opening(tmp_path, door):
    """A door swing on the wall layer used to become a wall triangle, and a
    door drawn over an unbroken wall was ignored ('not in a wall gap'): the
    rooms were sealed from each other. The door is found and its opening
    cut, so the two rooms are one free space joined through it."""
    from mapkit.importers import load_scene
    from mapkit.shapes import polygon_parts

    scene = load_scene(_two_rooms(tmp_path / f"{door}.dxf", door))
    doors = [o for o in scene.openings if o.kind == "door"]
    assert len(doors) == 1
    lo_x, lo_y, hi_x, hi_y = doors[0].footprint.bounds
    assert lo_x <= 4.0 <= hi_x and abs(lo_y - 1.0) < 0.05 and abs(hi_y - 1.9) < 0.05
    assert len(polygon_parts(scene.free_space)) == 1
    if door == "swing":
        assert any("1 door swing(s)" in w for w in scene.info["warnings"])
    assert any("over an unbroken wall" in w for w in scene.info["warnings"])


def test_a_rounded_corner_is_no_door_swing():
    """An arc joining two straight walls (a rounded corner) meets them along
    its tangent; a door's leaf crosses its arc. Only the leaf makes a swing."""
    from mapkit.importers.dxf.door_swings import find_door_swings

    doc = ezdxf.new("R2013")
    msp = doc.modelspace()
    msp.add_line((0, 0), (3, 0))
    msp.add_arc((3, 1), 1.0, 270, 360)  # from (3, 0) round to (4, 1)
    msp.add_line((4, 1), (4, 4))
    assert find_door_swings(list(msp), 1.0) == []
    msp.add_line((3, 1), (4, 1))  # a leaf from the centre to the arc's end, across it
    assert len(find_door_swings(list(msp), 1.0)) == 1


def _sheet(tmp_path):
    """The flat drawn twice on one sheet, the copy 30 m to the right of it
    (two storeys side by side, as the Indian house of the corpus)."""
    doc = ezdxf.readfile(FLAT)
    msp = doc.modelspace()
    for e in list(msp):
        copy = e.copy()
        try:
            copy.translate(30_000.0, 0.0, 0.0)  # millimetres
        except (NotImplementedError, AttributeError, TypeError):
            continue
        msp.add_entity(copy)
    path = tmp_path / "sheet.dxf"
    doc.saveas(path)
    return path


@pytest.mark.slow
def test_a_sheet_of_two_plans_builds_one_and_names_the_other(tmp_path, capsys):
    """Two storeys side by side on one sheet were built as one floor twice
    as wide; the plans are found, the largest built with a warning naming
    the other, ``--plan N`` chooses, ``mapkit layers`` lists them."""
    sheet = _sheet(tmp_path)
    code, _, err = run(capsys, "build", sheet, "-o", tmp_path / "one.lmap", "-q")
    assert code == 0, err
    assert "the drawing holds 2 separate plans: #1 11 x 9 m at (0, -1); #2 11 x 9 m at (30, -1); building #1" in err
    # The flat alone is the committed example map (test_build_real checks it is flat.dxf's build).
    one, flat = load_map(tmp_path / "one.lmap"), load_map(FLAT.with_suffix(".lmap"))
    assert np.array_equal(one.segments, flat.segments) and one.n_regions == flat.n_regions

    code, _, err = run(capsys, "build", sheet, "-o", tmp_path / "two.lmap", "-q", "--plan", "2")
    assert code == 0, err
    two = load_map(tmp_path / "two.lmap")
    assert np.allclose(two.segments - [30.0, 0.0, 0.0], flat.segments)
    assert two.meta["build"]["plan_number"] == 2 and "plan_number" not in flat.meta["build"]

    code, _, err = run(capsys, "build", sheet, "-o", tmp_path / "three.lmap", "--plan", "3")
    assert code == 2 and "--plan 3: the drawing holds 2 plan(s): #1 11 x 9 m" in err
    assert not (tmp_path / "three.lmap").exists()
    code, out, _ = run(capsys, "layers", sheet)
    assert code == 0 and "plans: 2 separate plans" in out and "#2  11.0 x 9.1 m at (30.0, -0.6)" in out


def test_layers_lists_the_plans_of_a_sheet_reading_the_file_once(tmp_path, capsys, monkeypatch):
    """'mapkit layers' found a sheet's plans by importing the drawing a
    second time after its layer table had read it: on a large drawing the
    listing took as long as two imports. The file is parsed once and the
    plans are listed as before."""
    sheet = _sheet(tmp_path)
    reads = []
    readfile = ezdxf.readfile
    monkeypatch.setattr(ezdxf, "readfile", lambda *a, **k: reads.append(a[0]) or readfile(*a, **k))
    code, out, err = run(capsys, "layers", sheet)
    assert code == 0, err
    assert "plans: 2 separate plans" in out and "#2  11.0 x 9.1 m at (30.0, -0.6)" in out
    assert len(reads) == 1, reads


def _zoned_rooms(path):
    """Two 4 x 4 m rooms in double-line walls 0.2 m thick (A-WALL), each
    also drawn as a room polygon on a room layer (a facility-management
    plan's room fills), the shared wall at x 3.9-4.1 broken for a door
    (y 1-1.9, A-DOOR: a leaf and its swing)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    wall, room, leaf = {"layer": "A-WALL"}, {"layer": "Rooms"}, {"layer": "A-DOOR"}
    msp.add_lwpolyline([(0, 0), (8.2, 0), (8.2, 4.2), (0, 4.2)], close=True, dxfattribs=wall)
    for x0, x1 in ((0.2, 3.9), (4.1, 8.0)):
        msp.add_lwpolyline([(x0, 0.2), (x1, 0.2), (x1, 4.0), (x0, 4.0)], close=True, dxfattribs=room)
    msp.add_lwpolyline([(0.2, 0.2), (3.9, 0.2), (3.9, 1.0), (4.1, 1.0), (4.1, 0.2), (8.0, 0.2), (8.0, 4.0),
                        (4.1, 4.0), (4.1, 1.9), (3.9, 1.9), (3.9, 4.0), (0.2, 4.0)], close=True, dxfattribs=wall)
    # The hinge on the right room's side of the wall, the leaf open square.
    msp.add_line((4.1, 1.0), (5.0, 1.0), dxfattribs=leaf)
    msp.add_arc((4.1, 1.0), 0.9, 0, 90, dxfattribs=leaf)
    doc.saveas(path)
    return path


def test_room_fills_do_not_wall_up_the_doorways(tmp_path):
    """A plan with a room polygon per room took the strips between them for
    walls, the door gaps among them (a university floor: 4 of 36 door
    drawings found); where a door sits in a gap of the walls as drawn, the
    strip is the door's gap."""
    from mapkit.importers import load_scene
    from mapkit.shapes import polygon_parts

    scene = load_scene(_zoned_rooms(tmp_path / "zoned.dxf"))
    assert [o.kind for o in scene.openings] == ["door"]
    assert len(polygon_parts(scene.free_space)) == 1


@pytest.mark.slow
def test_a_plan_too_small_for_free_space_names_the_units(tmp_path, capsys):
    """A plan drawn in centimetres that says millimetres was refused naming
    only the wall layers and the robot radius; the refusal says what the
    plan measures as read and names the --units that makes it a building's
    size, and with that option it builds. (With its doors drawn, the
    doors' widths say the units: tests/test_drawings_units.py; without
    them its doorway gaps: tests/test_drawings_gap_units.py; here the
    header's unit is also given as --units, which neither overrules.)"""
    doc = ezdxf.readfile(FLAT)
    msp = doc.modelspace()
    for e in list(msp):
        if e.dxf.layer == "A-DOOR":
            msp.delete_entity(e)
            continue
        try:
            e.scale_uniform(0.1)
        except (NotImplementedError, AttributeError, TypeError):
            pass
    small = tmp_path / "small.dxf"
    doc.saveas(small)
    code, _, err = run(capsys, "build", small, "-o", tmp_path / "small.lmap", "--units", "mm")
    assert code == 2 and ("the walls span only 1.2 x 1.0 m as read in mm (--units mm): if it is "
                          "drawn in cm, give --units cm (then 12 x 10 m)") in err
    assert not (tmp_path / "small.lmap").exists()
    code, _, err = run(capsys, "build", small, "-o", tmp_path / "small.lmap", "--units", "cm", "-q")
    assert code == 0, err


def _corridor_at_a_tenth(path):
    """A 40 x 3 m corridor in double-line walls 0.2 m thick drawn at a
    tenth of its size in a file that says metres (depthmapX's gallery, 4.6 m
    across so read): no unit makes it a building, a scale does."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (4.0, 0), (4.0, 0.3), (0, 0.3)], close=True, dxfattribs={"layer": "A-WALL"})
    msp.add_lwpolyline([(0.02, 0.02), (3.98, 0.02), (3.98, 0.28), (0.02, 0.28)], close=True,
                       dxfattribs={"layer": "A-WALL"})
    doc.saveas(path)
    return path


def test_a_plan_drawn_at_a_tenth_in_metres_is_refused_naming_the_scale(tmp_path, capsys):
    """Refused with no free space, the gallery's message said only 'if the
    drawing is in other units, give them with --units or --scale'; no unit
    makes a 4 m plan in metres a building, so it names the --scale that
    does, and with that scale the plan has its free space."""
    from mapkit.importers import load_scene
    from mapkit.options import BuildOptions

    corridor = _corridor_at_a_tenth(tmp_path / "corridor.dxf")
    code, out, err = run(capsys, "build", corridor, "-o", tmp_path / "corridor.lmap")
    assert_one_line_error(code, out, err, "no free space left inside the walls")
    assert ("the walls span only 4.0 x 0.3 m as read in m (its $INSUNITS 6 says m): if it is drawn at 1/10 of its "
            "size, give --scale 10 (then 40 x 3 m)") in err
    assert not (tmp_path / "corridor.lmap").exists()
    scene = load_scene(corridor, BuildOptions(scale=10))
    assert scene.free_space.area == pytest.approx((39.6 - 0.4) * (2.6 - 0.4), rel=0.01)


@pytest.mark.parametrize("unit, insunits, override, scale, says", [
    ("mm", 4, None, 1.0, "as read in mm (its $INSUNITS 4 says mm): if it is drawn in cm, give --units cm (then 12 x 8 m)"),
    ("in", 1, None, 1.0, "as read in in (its $INSUNITS 1 says in): if it is drawn in ft, give --units ft (then 14 x 10 m)"),
    ("m", 6, "m", 1.0, "as read in m (--units m): if it is drawn at 1/10 of its size, give --scale 10 (then 12 x 8 m)"),
    ("m", 0, None, 2.0, "as read in m (assumed from its extent, $INSUNITS 0): if it is drawn at 1/10 of its size, "
                        "give --scale 20 (then 12 x 8 m)"),
])
def test_the_rescale_hint_names_the_unit_of_the_same_system_or_a_scale(unit, insunits, override, scale, says):
    from mapkit.importers.dxf.units import rescale_hint

    assert rescale_hint(1.2, 0.8, unit, insunits, override, scale) == f"the walls span only 1.2 x 0.8 m {says}"
