"""A storey drawn one layer per room whose living room's own outline stays
open (issue 34: the Indian house smh_dxf28, 'LivingRoom2' drawn as three
lines, its fourth side the staircase's walls, an open-to-sky void 'OTS' and
a bathroom's open doorway). A person reading the plan sees the room those
close; the free space was the bedrooms only, in two parts. Each drawing is
written here with ezdxf, in metres."""

from __future__ import annotations

import json

import ezdxf
import pytest
from shapely.geometry import box

from cli_helpers import run
from mapkit.importers import load_scene
from mapkit.shapes import polygon_parts


def _lines(msp, layer: str, *points):
    """A polyline of LINEs on ``layer`` through ``points``."""
    for p, q in zip(points, points[1:]):
        msp.add_line(p, q, dxfattribs={"layer": layer})


def _storey(path, void: bool):
    """Two bedrooms 4 x 4 m ('BedRoom1', 'BedRoom1a') with a 2 m walkway
    between them (its bottom line on 'Walkway'), a door line 0.9 m wide from
    each into the walkway, a third bedroom 3 x 4 m ('BedRoom2a') east of
    them with a door line from the second; above the first two the living
    room, 'LivingRoom1' drawn as three lines (north, east, and south over
    the second bedroom), open to the west. West of it a staircase 3 x 3 m
    on 'Staircase_wall' (west side, and a north wall of two lines 0.15 m
    apart whose east end is not drawn), open to the living room; above the
    staircase 'BedRoom2', a room whose east side has a doorway 0.95 m wide
    with no door drawn in it. With ``void``, an open-to-sky void 'OTS' (a
    closed rectangle of lines, 1.85 x 0.9 m) east of that room's north end
    closes the living room's north-west corner, as in the Indian house."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    _lines(msp, "BedRoom1", (4, 2.5), (4, 0), (0, 0), (0, 4), (4, 4), (4, 3.4))
    _lines(msp, "BedRoom1a", (6, 2.5), (6, 0), (10, 0), (10, 1))
    _lines(msp, "BedRoom1a", (10, 1.9), (10, 4), (6, 4), (6, 3.4))
    _lines(msp, "BedRoom2a", (10, 1), (10, 0), (13, 0), (13, 4), (10, 4), (10, 1.9))
    _lines(msp, "Walkway", (4, 0), (6, 0))
    for x in (4, 6):
        _lines(msp, "Door3fD.Panel", (x, 2.5), (x, 3.4))
    _lines(msp, "Door3fD.Panel", (10, 1), (10, 1.9))
    _lines(msp, "Staircase_wall", (0, 4), (0, 7), (3, 7))
    _lines(msp, "BedRoom2", (3, 8.1), (3, 9), (0, 9), (0, 7.15), (3, 7.15))
    if void:
        _lines(msp, "OTS", (3.15, 8.1), (5, 8.1), (5, 9), (3.15, 9), (3.15, 8.1))
        _lines(msp, "BedRoom2", (3, 8.1), (3.15, 8.1))
        _lines(msp, "LivingRoom1", (5, 9), (10, 9), (10, 4), (6, 4))
    else:
        _lines(msp, "LivingRoom1", (3, 9), (10, 9), (10, 4), (6, 4))
    doc.saveas(path)
    return path


@pytest.mark.parametrize("void", [False, True])
def test_a_room_whose_outline_the_walls_around_it_close_is_a_room(tmp_path, void):
    """Wrong before: the living room's lines enclose no face, so the rooms
    were the bedrooms only, two parts of free space; the living room that
    the staircase's wall (its open end a wall's end), the room beside it
    and the void close is a room too, doors open into it: one part, the
    living room, the walkway, the staircase and the room whose doorway has
    no door in it; not the void, which no door opens into."""
    scene = load_scene(_storey(tmp_path / "storey.dxf", void))
    assert scene.info["interior"] == "room outlines"
    assert [o.kind for o in scene.openings] == ["door"] * 3
    assert len(polygon_parts(scene.free_space)) == 1
    for where in (box(5, 6, 9, 7.8), box(4.5, 1, 5.5, 3), box(1, 5, 2, 6), box(0.3, 7.5, 2.7, 8.7)):
        assert scene.free_space.intersection(where).area == pytest.approx(where.area)
    # Nothing outside the storey, nothing of the void.
    assert scene.free_space.difference(box(0, 0, 13, 9)).area == 0
    if void:
        assert scene.free_space.intersection(box(3.15, 8.1, 5, 9)).area == 0


def test_a_void_named_in_a_plan_of_one_layer_per_room_is_walls(tmp_path, capsys):
    """'OTS' (open to sky) says nothing of a role a layer of its own would
    have; in a drawing of one layer per room it is a space the rooms are
    drawn around, its outline walls ('mapkit layers' says why)."""
    code, out, err = run(capsys, "layers", _storey(tmp_path / "storey.dxf", True), "--json")
    assert code == 0, err
    rows = {r["name"]: r for r in json.loads(out)["layers"]}
    assert rows["OTS"]["role"] == "walls"
    assert "named for a room or a space" in rows["OTS"]["why"]


@pytest.mark.parametrize("name", ["OTS", "Open_to_sky", "Void", "Shaft2", "Courtyard"])
def test_void_names_are_spaces(name):
    from mapkit.importers.dxf.room_layers import is_general_space_name, is_space_name

    assert is_space_name(name)
    assert not is_general_space_name(name)  # alone (no per-room drawing) not a room outline
