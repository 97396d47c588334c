"""`mapkit info`, `query`, `export`: outputs and every user error (one line, exit 2)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_helpers import assert_one_line_error, run, run_with_reader_gone
import shapely.geometry.polygon
from shapely.geometry import box

from mapkit.assemble import assemble_map
from mapkit.cli import main
from linemap.lmap import SegmentKind, save_map


@pytest.fixture(scope="module")
def map_path(tmp_path_factory):
    """Two rooms side by side: region 0 sees segments 0-2, region 1 sees 2-4."""
    segs = np.array(
        [
            [[0, 0, 0], [2, 0, 0]],
            [[0, 0, 0], [0, 0, 2.5]],
            [[2, 0, 2.5], [2, 3, 2.5]],
            [[2, 3, 0], [4, 3, 0]],
            [[4, 0, 0], [4, 0, 2.5]],
        ],
        float,
    )
    kinds = [SegmentKind.FLOOR, SegmentKind.VERTICAL, SegmentKind.CEILING, SegmentKind.FLOOR, SegmentKind.JAMB]
    walls = box(-0.2, -0.2, 4.2, 3.2).difference(box(0, 0, 4, 3))
    m = assemble_map(segs, kinds, [box(0, 0, 2, 3), box(2, 0, 4, 3)], [[0, 1, 2], [2, 3, 4]], walls,
                     {"units": "m", "wall_height": 2.5, "source": {"name": "two.dxf", "sha256": "0", "bytes": 1}})
    path = tmp_path_factory.mktemp("maps") / "two.lmap"
    save_map(path, m)
    return path



def test_info_json(map_path, capsys):
    code, out, err = run(capsys, "info", map_path, "--json")
    assert code == 0 and err == ""
    info = json.loads(out)
    assert info["format_version"] == "1.0"
    assert info["segments"] == 5 and info["regions"] == 2
    assert info["segments_per_kind"]["floor"] == 2 and info["segments_per_kind"]["jamb"] == 1
    assert info["bbox"]["min"][:2] == pytest.approx([0, 0]) and info["bbox"]["max"] == pytest.approx([4, 3, 2.5])
    assert info["file_bytes"] == map_path.stat().st_size
    assert "build" in info


def test_info_human(map_path, capsys):
    code, out, _ = run(capsys, "info", map_path)
    assert code == 0 and "segments   5" in out and "regions    2" in out


@pytest.mark.parametrize(
    "at, radius, regions, segments",
    [("1,1", 0, [0], [0, 1, 2]), ("3,1", 0, [1], [2, 3, 4]), ("1.9,1", 0.2, [0, 1], [0, 1, 2, 3, 4]), ("9,9", 1, [], [])],
)
def test_query_json(map_path, capsys, at, radius, regions, segments):
    code, out, _ = run(capsys, "query", map_path, "--at", at, "--radius", radius, "--json")
    assert code == 0
    assert json.loads(out) == {"regions": regions, "segments": segments}


def test_query_with_negative_or_huge_numbers(map_path, capsys):
    code, out, err = run(capsys, "query", map_path, "--at", "-0.1,-0.1", "--radius", "0.5", "--json")
    assert code == 0 and json.loads(out)["regions"] == [0] and err == ""
    for at, radius in (("0,0", "1e308"), ("1e308,0", "0"), ("1e308,1e308", "1e308")):
        code, out, err = run(capsys, "query", map_path, "--at", at, "--radius", radius, "--json")
        assert code == 0 and err == "" and set(json.loads(out)) == {"regions", "segments"}


def test_export_geojson(map_path, tmp_path, capsys):
    out_path = tmp_path / "two.geojson"
    code, _, _ = run(capsys, "export", map_path, "--geojson", out_path)
    assert code == 0
    fc = json.loads(out_path.read_text())
    polys = [f for f in fc["features"] if f["geometry"]["type"] == "Polygon"]
    lines = [f for f in fc["features"] if f["geometry"]["type"] == "LineString"]
    assert [p["properties"] for p in polys] == [{"id": 0, "segments": [0, 1, 2]}, {"id": 1, "segments": [2, 3, 4]}]
    assert lines[4]["properties"] == {"id": 4, "kind": "jamb"}
    assert len(lines[1]["geometry"]["coordinates"][1]) == 3  # 3D coordinates
    ring = polys[0]["geometry"]["coordinates"][0]
    assert ring[0] == ring[-1]


def _signed_area(ring):
    return 0.5 * sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(ring, ring[1:]))


def test_export_geojson_winds_rings_as_rfc_7946_says(tmp_path, capsys):
    """Outer rings counter-clockwise, holes clockwise, whichever way the
    map stores them (a room with a pillar: a region with a hole)."""
    room = box(0, 0, 4, 3).difference(box(1.5, 1, 2, 1.5))
    segs = np.array([[[0, 0, 0], [4, 0, 0]], [[0, 0, 0], [0, 0, 2.5]]], float)
    walls = box(-0.2, -0.2, 4.2, 3.2).difference(box(0, 0, 4, 3))
    for region in (room, shapely.geometry.polygon.orient(room, -1.0)):
        m = assemble_map(segs, [SegmentKind.FLOOR, SegmentKind.VERTICAL], [region], [[0, 1]], walls,
                         {"units": "m", "wall_height": 2.5})
        save_map(tmp_path / "pillar.lmap", m)
        out_path = tmp_path / "pillar.geojson"
        assert run(capsys, "export", tmp_path / "pillar.lmap", "--geojson", out_path)[0] == 0
        _check_winding(out_path)


def _check_winding(out_path):
    polys = [f["geometry"]["coordinates"] for f in json.loads(out_path.read_text())["features"]
             if f["geometry"]["type"] == "Polygon"]
    assert all(_signed_area(rings[0]) > 0 for rings in polys)
    holes = [ring for rings in polys for ring in rings[1:]]
    assert holes and all(_signed_area(ring) < 0 for ring in holes)



def test_missing_map(tmp_path, capsys):
    assert_one_line_error(*run(capsys, "info", tmp_path / "nope.lmap"), "no such file")


def test_not_a_map(tmp_path, capsys):
    bad = tmp_path / "bad.lmap"
    bad.write_text("hello")
    assert_one_line_error(*run(capsys, "info", bad), "not a .lmap map")


def test_corrupt_map(map_path, tmp_path, capsys):
    data = bytearray(map_path.read_bytes())
    data[-5] ^= 0x55
    bad = tmp_path / "corrupt.lmap"
    bad.write_bytes(bytes(data))
    assert_one_line_error(*run(capsys, "query", bad, "--at", "1,1"), "checksum")


def test_truncated_map(map_path, tmp_path, capsys):
    bad = tmp_path / "cut.lmap"
    bad.write_bytes(map_path.read_bytes()[:100])
    assert_one_line_error(*run(capsys, "info", bad, "--json"), "truncated")


@pytest.mark.parametrize("at", ["1", "a,b", "1,2,3", "nan,1"])
def test_bad_at(map_path, capsys, at):
    assert_one_line_error(*run(capsys, "query", map_path, "--at", at), "--at")


def test_negative_radius(map_path, capsys):
    assert_one_line_error(*run(capsys, "query", map_path, "--at", "1,1", "--radius", "-1"), "--radius")


def test_export_into_missing_folder_writes_nothing(map_path, tmp_path, capsys):
    assert_one_line_error(*run(capsys, "export", map_path, "--geojson", tmp_path / "no" / "x.geojson"), "does not exist")
    assert not (tmp_path / "no").exists()


def test_unknown_option(map_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["info", str(map_path), "--frobnicate"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("mapkit: error: unrecognized arguments") and err.count("\n") == 1


def test_reader_gone_is_quiet(map_path):
    """`mapkit info MAP --json | head -0`: stdout's reader has gone; no error, no traceback."""
    out = run_with_reader_gone("-m", "mapkit", "info", map_path, "--json")
    assert out.returncode == 0 and out.stderr == ""
