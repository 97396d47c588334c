"""DXF import: reading (and refusing) files, units, layer roles, entity flattening.

The small files in tests/data/dxf/ are written by tests/data/dxf/make_cases.py;
each isolates one thing real drawings do.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
import pytest

from mapkit.errors import MapkitError, NoWallsError
from mapkit.importers.dxf import load_drawing, load_scene
from mapkit.importers.dxf.units import decide_units
from mapkit.units import parse_units
from mapkit.importers.dxf.layer_roles import assign_roles, guess_role
from mapkit.options import BuildOptions
from mapkit.tolerances import CURVE_SAGITTA, CURVE_STEP_DEG

CASES = Path(__file__).resolve().parent / "data" / "dxf"


def _bounds(strokes) -> np.ndarray:
    pts = np.concatenate([s.coords for s in strokes])
    return np.r_[pts.min(axis=0), pts.max(axis=0)]


# ---- units -------------------------------------------------------------------


def test_millimetre_header_is_converted_to_metres():
    drawing, info = load_drawing(CASES / "room_mm.dxf", BuildOptions())
    assert info["units"] == "mm" and info["scale"] == pytest.approx(0.001)
    np.testing.assert_allclose(_bounds(drawing.role("walls")), [0, 0, 10, 8], atol=1e-9)
    assert info["warnings"] == []


def test_units_option_overrides_the_header():
    drawing, info = load_drawing(CASES / "room_mm.dxf", BuildOptions(units="cm"))
    assert info["units"] == "cm"
    np.testing.assert_allclose(_bounds(drawing.role("walls")), [0, 0, 100, 80], atol=1e-9)


def test_scale_multiplies_after_units():
    drawing, info = load_drawing(CASES / "room_mm.dxf", BuildOptions(scale=0.5))
    np.testing.assert_allclose(_bounds(drawing.role("walls")), [0, 0, 5, 4], atol=1e-9)


def test_missing_units_are_guessed_from_the_extent_with_a_warning(caplog):
    with caplog.at_level(logging.WARNING, logger="mapkit"):
        drawing, info = load_drawing(CASES / "room_mm_unitless.dxf", BuildOptions())
    assert info["units"] == "mm"
    np.testing.assert_allclose(_bounds(drawing.role("walls")), [0, 0, 10, 8], atol=1e-9)
    (warning,) = [w for w in info["warnings"] if "no units" in w]
    assert "assumed mm" in warning and "--units" in warning
    assert warning in caplog.text


@pytest.mark.parametrize(
    ("extent", "expected"),
    [(27.0, "m"), (45.0, "m"), (27000.0, "mm"), (150000.0, "mm"), (2700.0, "cm"), (5.0, "m")],
)
def test_unitless_guess_picks_a_building_sized_unit(extent, expected):
    name, factor, warning = decide_units(0, None, extent)
    assert name == expected
    assert "assumed" in warning


def test_unitless_imperial_drawing_guesses_inches_or_feet():
    assert decide_units(0, None, 540.0, imperial=True)[0] == "in"  # a 45 ft house in inches
    assert decide_units(0, None, 45.0, imperial=True)[0] == "ft"


def test_implausible_units_are_refused_with_the_likely_ones():
    # A house drawn in mm but labelled metres: 27000 "m" is 27 km across.
    with pytest.raises(MapkitError, match=r"units are m but then the plan is 27 km across, not a building "
                                          r"\(1 m to 2 km\); pass the right --units \(in mm it is 27 m across\)"):
        decide_units(6, None, 27000.0)
    with pytest.raises(MapkitError, match=r"--units says mm but then the plan is 0.045 m across.*in m it is 45 m"):
        decide_units(0, "mm", 45.0)
    assert decide_units(6, None, 27.0)[2] is None


def test_unknown_units_name_is_a_user_error():
    assert parse_units("Millimetres") == pytest.approx(0.001)
    assert parse_units("feet") == pytest.approx(0.3048)
    with pytest.raises(MapkitError, match="unknown units 'furlong'; use one of"):
        parse_units("furlong")


# ---- entities ------------------------------------------------------------------


def test_bulge_is_flattened_within_the_curve_tolerances():
    drawing, _ = load_drawing(CASES / "bulge_apse.dxf", BuildOptions())
    (stroke,) = drawing.role("walls")
    assert stroke.closed
    pts = stroke.coords
    # The bulge (6,0)->(6,4) is a half circle about (6,2), radius 2, bulging east.
    arc = pts[(pts[:, 0] > 6 + 1e-9)]
    radii = np.hypot(arc[:, 0] - 6, arc[:, 1] - 2)
    # Vertices lie on the Bezier approximation of the arc, within 1e-4 m of it.
    np.testing.assert_allclose(radii, 2.0, atol=1e-4)
    ring = np.vstack([[6, 0], arc, [6, 4]])
    ang = np.degrees(np.arctan2(ring[:, 1] - 2, ring[:, 0] - 6))
    steps = np.abs(np.diff(ang))
    assert steps.max() <= CURVE_STEP_DEG + 1e-6
    chord_sagitta = 2.0 * (1 - np.cos(np.radians(steps / 2)))
    assert chord_sagitta.max() + 1e-4 <= CURVE_SAGITTA
    # Area: 6 x 4 rectangle plus a half disc of radius 2 (chords lose a little).
    x, y = pts[:, 0], pts[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert 24 + 2 * math.pi - 0.05 < area <= 24 + 2 * math.pi


def test_nested_block_on_layer_0_takes_the_insert_layer_and_is_one_group():
    drawing, info = load_drawing(CASES / "nested_blocks.dxf", BuildOptions())
    doors = drawing.role("doors")
    assert len(doors) == 2  # leaf + arc, two blocks deep
    assert {s.layer for s in doors} == {"A-DOOR"}
    assert len({s.group for s in doors}) == 1 and doors[0].group is not None
    assert info["layers"]["doors"] == ["A-DOOR"]
    assert "A-ANNO" in info["layers"]["ignored"]


def test_mirrored_rotated_insert_lands_where_cad_draws_it():
    drawing, _ = load_drawing(CASES / "nested_blocks.dxf", BuildOptions())
    leaf, arc = sorted(drawing.role("doors"), key=lambda s: len(s.coords))
    # DOORSET at (2, 3), rotated 90 degrees, x mirrored: see make_cases.nested_blocks.
    np.testing.assert_allclose(sorted(map(tuple, leaf.coords)), [(1.1, 2.95), (2.0, 2.95)], atol=1e-9)
    np.testing.assert_allclose(np.hypot(arc.coords[:, 0] - 2.0, arc.coords[:, 1] - 2.95), 0.9, atol=1e-9)
    ends = {tuple(np.round(arc.coords[i], 9)) for i in (0, -1)}
    assert ends == {(2.0, 2.05), (1.1, 2.95)}
    # The swing lies on the -x, -y side of the hinge (mirrored, then rotated).
    assert (arc.coords[:, 0] <= 2.0 + 1e-9).all() and (arc.coords[:, 1] <= 2.95 + 1e-9).all()


def test_minsert_array_gives_one_solid_per_cell():
    drawing, _ = load_drawing(CASES / "nested_blocks.dxf", BuildOptions())
    cols = [s for s in drawing.role("walls") if s.layer == "A-COLS"]
    assert len(cols) == 6 and all(s.closed for s in cols)
    origins = sorted(tuple(np.round(s.coords.min(axis=0), 9)) for s in cols)
    assert origins == [(x, y) for x in (10.0, 14.0, 18.0) for y in (0.0, 5.0)]
    assert len({s.group for s in cols}) == 6


def test_unsupported_entities_are_counted_in_one_warning(caplog):
    with caplog.at_level(logging.WARNING, logger="mapkit"):
        _, info = load_drawing(CASES / "unsupported.dxf", BuildOptions())
    skipped = [w for w in info["warnings"] if "unsupported" in w]
    assert skipped == ["skipped unsupported entities: 2 3DFACE"]  # MTEXT is skipped silently
    assert caplog.text.count("unsupported") == 1


# ---- files that are not (good) DXF ------------------------------------------


def test_damaged_file_is_recovered_with_a_warning():
    scene = load_scene(CASES / "damaged_no_eof.dxf", BuildOptions())
    assert any("damaged" in w for w in scene.info["warnings"])
    assert scene.walls.area > 0 and scene.free_space.area > 50


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("not_a_dxf.dxf", r"not_a_dxf\.dxf: not a DXF file"),
        ("truncated.dxf", r"truncated\.dxf: the file is damaged or truncated"),
        ("empty.dxf", r"empty\.dxf: the drawing is empty"),
    ],
)
def test_unreadable_files_are_one_line_user_errors(name, message):
    with pytest.raises(MapkitError, match=message) as exc:
        load_scene(CASES / name, BuildOptions())
    assert "\n" not in str(exc.value)


def test_zero_byte_file_is_a_user_error(tmp_path):
    path = tmp_path / "zero.dxf"
    path.write_bytes(b"")
    with pytest.raises(MapkitError, match="the file is empty"):
        load_scene(path, BuildOptions())


# ---- layer roles -------------------------------------------------------------


@pytest.mark.parametrize(
    ("layer", "role"),
    [
        ("Walls", "walls"), ("A-WALL", "walls"), ("A-WALL-PRTN", "walls"), ("Wände", "walls"), ("MURS", "walls"),
        ("muro", "walls"), ("Columns", "walls"), ("A-COLS", "walls"), ("Stütze", "walls"), ("pilier", "walls"),
        ("structure", "walls"), ("outerWalls", "walls"),
        ("Doors", "doors"), ("A-DOOR", "doors"), ("Tür", "doors"), ("porte", "doors"), ("puertas", "doors"),
        ("A-GLAZ", "windows"), ("Fenster", "windows"), ("fenêtre", "windows"), ("Crystal", "windows"),
        ("vitre", "windows"), ("glazing", "windows"),
        ("Flooring", "floor"),
        ("Furniture", "ignore"), ("A-FURN", "ignore"), ("A-ANNO-TEXT", "ignore"), ("dimensions", "ignore"),
        ("A-FLOR-PATT", "ignore"), ("A-WALL-TEXT", "ignore"),
        ("s001-#def-active-grp", None), ("0", None),
    ],
)
def test_role_guessing(layer, role):
    assert guess_role(layer) == role


def test_explicit_globs_are_case_insensitive_and_replace_guessing_for_their_role():
    layers = ["Walls", "Columns", "Crystal", "Doors", "furniture", "Wand-2"]
    roles = assign_roles(layers, walls=["WALL*", "col*"], doors=[], windows=[], ignore=["FURN*"])
    assert roles["Walls"] == "walls" and roles["Columns"] == "walls"
    assert roles["Wand-2"] == "ignore"  # named like a wall, but --walls says which layers are walls
    assert roles["Doors"] == "doors" and roles["Crystal"] == "windows"  # still guessed
    assert roles["furniture"] == "ignore"


def test_single_unnamed_layer_is_taken_as_walls_with_a_warning():
    drawing, info = load_drawing(Path(__file__).parent / "data" / "thehouse.dxf", BuildOptions())
    assert info["layers"]["walls"] == ["s001-#def-active-grp"]
    assert any("using the only drawing layer" in w for w in info["warnings"])


def test_no_walls_lists_the_layers_and_suggests_walls_option():
    with pytest.raises(NoWallsError, match=r"no recognisable walls: layers are .*'Doors', 'Furniture'.*--walls"):
        load_scene(CASES / "no_walls.dxf", BuildOptions())


def test_glob_matching_no_layer_is_a_user_error():
    with pytest.raises(MapkitError, match=r"--walls Wal matches no layer; layers are: .*'Walls'"):
        load_scene(CASES / "room_mm.dxf", BuildOptions(walls=["Wal"]))
