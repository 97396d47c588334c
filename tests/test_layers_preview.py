"""`mapkit layers` and `mapkit preview` through the CLI: output, exit codes, one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_helpers import assert_one_line_error, run

DATA = Path(__file__).resolve().parent / "data"
CASES = DATA / "dxf"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"




# ---- layers --------------------------------------------------------------------


def test_layers_table_lists_every_layer_with_counts_and_role(capsys):
    code, out, err = run(capsys, "layers", DATA / "barcelona-pavilion.dxf")
    assert code == 0, err
    rows = {ln.split()[0]: ln.split() for ln in out.splitlines()[1:]}
    assert out.splitlines()[0].split() == ["LAYER", "ROLE", "COUNT", "ENTITIES", "WHY"]
    assert rows["Walls"][1:4] == ["walls", "60", "LINE"]
    assert rows["Doors"][1:7] == ["doors", "118", "ARC", "8,", "LINE", "110"]
    assert " ".join(rows["Doors"][7:]).startswith("'doors':")  # why: the word of its name
    assert rows["Crystal"][1] == "windows" and rows["Flooring"][1] == "floor"
    assert rows["Furniture"][1] == "ignored" and rows["Defpoints"][2] == "0"


def test_layers_json_is_one_object_and_honours_layer_options(capsys):
    code, out, err = run(capsys, "layers", DATA / "barcelona-pavilion.dxf", "--json", "--walls", "walls", "--ignore", "Crystal")
    assert code == 0, err
    doc = json.loads(out)
    roles = {row["name"]: row["role"] for row in doc["layers"]}
    assert roles["Walls"] == "walls"
    assert roles["Columns"] == "ignored"  # --walls names the wall layers
    assert roles["Crystal"] == "ignored"
    furniture = next(row for row in doc["layers"] if row["name"] == "Furniture")
    assert furniture["entities"] == {"ARC": 61, "CIRCLE": 188, "LINE": 201} and furniture["total"] == 450


def test_layers_reports_the_single_layer_fallback(capsys):
    code, out, _ = run(capsys, "layers", DATA / "thehouse.dxf")
    assert code == 0
    assert "s001-#def-active-grp  walls" in out
    assert "note: no layer is named like walls" in out


def test_layers_still_lists_a_plan_without_walls(capsys):
    code, out, _ = run(capsys, "layers", CASES / "no_walls.dxf")
    assert code == 0
    assert "Furniture" in out and "note: no recognisable walls" in out and "--walls" in out


@pytest.mark.parametrize(
    ("name", "needle"),
    [("not_a_dxf.dxf", "not a DXF file"), ("truncated.dxf", "damaged or truncated"), ("missing.dxf", "no such file")],
)
def test_layers_bad_input_is_a_one_line_error(capsys, name, needle):
    assert_one_line_error(*run(capsys, "layers", CASES / name), needle)


def test_layers_refuses_meshes(capsys, tmp_path):
    mesh = tmp_path / "room.stl"
    mesh.write_text("solid x\nendsolid x\n")
    assert_one_line_error(*run(capsys, "layers", mesh), "reads DXF plans")


# ---- preview -------------------------------------------------------------------


def test_preview_writes_a_png_and_says_what_it_understood(capsys, tmp_path):
    out_png = tmp_path / "house.png"
    code, out, err = run(capsys, "preview", DATA / "thehouse.dxf", "-o", out_png, "--walls", "s001-*", "--dpi", "40")
    assert code == 0, err
    assert out_png.read_bytes()[:8] == PNG_SIGNATURE
    assert out.startswith(f"wrote {out_png}: walls ") and "0 doors" in out and "s001-#def-active-grp" in out
    assert len(out.splitlines()) == 1
    # The unitless drawing is reported as a warning line, not an error.
    assert "mapkit: warning: the drawing has no units" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["house.png"]  # no temporary left


@pytest.mark.slow
def test_preview_draws_openings_and_ignored_layers(capsys, tmp_path):
    out_png = tmp_path / "pavilion.png"
    code, out, err = run(
        capsys, "preview", DATA / "barcelona-pavilion.dxf", "-o", out_png,
        "--walls", "Walls", "--walls", "Columns", "--windows", "Crystal", "--dpi", "40",
    )
    assert code == 0, err
    assert out_png.stat().st_size > 5000
    assert "doors" in out and "windows: Crystal" in out


def test_preview_replaces_an_existing_file_whole(capsys, tmp_path):
    out_png = tmp_path / "p.png"
    out_png.write_bytes(b"old")
    assert run(capsys, "preview", DATA / "thehouse.dxf", "-o", out_png, "--dpi", "30")[0] == 0
    assert out_png.read_bytes()[:8] == PNG_SIGNATURE


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        ([CASES / "not_a_dxf.dxf"], "not a DXF file"),
        ([CASES / "truncated.dxf"], "damaged or truncated"),
        ([CASES / "empty.dxf"], "drawing is empty"),
        ([CASES / "no_walls.dxf"], "no recognisable walls"),
        ([DATA / "thehouse.dxf", "--walls", "nope*"], "--walls nope* matches no layer"),
        ([DATA / "thehouse.dxf", "--units", "mm"], "in m it is 44.7 m across"),
        ([DATA / "thehouse.dxf", "--robot-radius", "-1"], "--robot-radius"),
    ],
)
def test_preview_user_errors_are_one_line_and_write_nothing(capsys, tmp_path, args, needle):
    out_png = tmp_path / "p.png"
    assert_one_line_error(*run(capsys, "preview", *args, "-o", out_png), needle)
    assert list(tmp_path.iterdir()) == []


def test_preview_output_must_be_png_in_an_existing_folder(capsys, tmp_path):
    assert_one_line_error(*run(capsys, "preview", DATA / "thehouse.dxf", "-o", tmp_path / "p.jpg"), ".png")
    assert_one_line_error(*run(capsys, "preview", DATA / "thehouse.dxf", "-o", tmp_path / "no" / "p.png"), "does not exist")
    assert list(tmp_path.iterdir()) == []


def test_no_walls_error_lists_layers_and_suggests_the_option(capsys, tmp_path):
    code, out, err = run(capsys, "preview", CASES / "no_walls.dxf", "-o", tmp_path / "p.png")
    assert_one_line_error(code, out, err, "'Doors'", "'Furniture'", "--walls", "mapkit layers")


def test_layers_on_a_directory_or_a_mesh_says_which(tmp_path, capsys):
    assert_one_line_error(*run(capsys, "layers", tmp_path), "is a directory, expected a DXF file")
    assert_one_line_error(*run(capsys, "layers", DATA / "hospital.stl"), "reads DXF plans (.dxf), got a '.stl' file")
