"""ZInD annotations -> map: a two-room ZInD-shaped file written here (no ZInD data is shipped).

World (metres, right-handed): room A x 0..5, y 0..4, ceiling 2.5 m; room B
x 5.2..9.2, y 0..4, ceiling 2.4 m; a door between them (y 1..2, annotated
from both rooms), a window in A's north wall (x 1..2.5, 0.9 to 2.1 m), an
opening in B's south wall (x 6..8, floor to ceiling). ZInD's plan is the world
mirrored (y negated); each panorama's frame is the plan shifted to the
panorama and divided by its scale (1.25 m per unit: camera height 1.25 m).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_helpers import assert_one_line_error, run

from linemap.lmap import SegmentKind
from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.pipeline import build_map

UNIT = 1.25  # metres per panorama unit (transformation scale 1.25, 1 m per plan coordinate)


def _local(points_world, centre_world):
    """World points (n, 2) -> a panorama's frame (rotation 0) centred at ``centre_world``."""
    p = (np.asarray(points_world, float) - centre_world) * (1.0, -1.0)
    return (p / UNIT).tolist()


def _gap(a, b, bottom_m, top_m, centre):
    """ZInD's triple for a gap from a to b (world), heights in metres above the floor."""
    ends = _local([a, b], centre)
    return [ends[0], ends[1], [bottom_m / UNIT - 1.0, top_m / UNIT - 1.0]]


def _pano(centre, outline, ceiling_m, doors=(), windows=(), openings=(), primary=True):
    layout = {
        "vertices": _local(outline, centre),
        "doors": [p for g in doors for p in _gap(*g, centre)],
        "windows": [p for g in windows for p in _gap(*g, centre)],
        "openings": [p for g in openings for p in _gap(*g, centre)],
        "internal": [],
    }
    return {
        "label": "room", "is_primary": primary, "is_inside": True, "is_ceiling_flat": True,
        "ceiling_height": ceiling_m / UNIT, "camera_height": 1.0, "floor_number": 1,
        "image_path": "panos/none.jpg", "layout_raw": layout, "layout_complete": layout,
        "floor_plan_transformation": {"translation": [centre[0], -centre[1]], "rotation": 0.0, "scale": UNIT},
    }


def zind_doc(floors=("floor_01",), recess=False):
    a_centre, b_centre = np.array([2.5, 2.0]), np.array([7.2, 2.0])
    room_a = [(0, 0), (5, 0), (5, 4), (0, 4)]
    room_b = [(5.2, 0), (9.2, 0), (9.2, 4), (5.2, 4)]
    door_a = ((5.0, 1.0), (5.0, 2.0), 0.0, 2.0)
    door_b = ((5.2, 2.0), (5.2, 1.0), 0.0, 2.0)  # the same door seen from B
    window = ((1.0, 4.0), (2.5, 4.0), 0.9, 2.1)
    opening = ((6.0, 0.0), (8.0, 0.0), 0.0, 2.45)  # annotated a little above the ceiling
    floor = {
        "complete_room_01": {"partial_room_01": {"pano_1": _pano(a_centre, room_a, 2.5, [door_a], [window])}},
        "complete_room_02": {"partial_room_02": {"pano_2": _pano(b_centre, room_b, 2.4, [door_b], [], [opening])}},
    }
    if recess:  # B annotates an opening in the wall it shares with A, which A does not
        floor["complete_room_02"]["partial_room_02"]["pano_2"] = _pano(
            b_centre, room_b, 2.4, [door_b], [], [opening, ((5.2, 3.6), (5.2, 3.0), 0.0, 2.4)])
    return {
        "scale_meters_per_coordinate": {f: 1.0 for f in floors},
        "merger": {f: floor for f in floors},
        "redraw": {f: {} for f in floors},
    }


@pytest.fixture
def zind_file(tmp_path):
    path = tmp_path / "zind_data.json"
    path.write_text(json.dumps(zind_doc()))
    return path


def test_rooms_heights_openings_and_free_space(zind_file):
    scene = load_scene(zind_file, BuildOptions(robot_radius=0.0))
    assert scene.camera_height == pytest.approx(1.25)
    assert sorted(z.height for z in scene.height_zones) == pytest.approx([2.4, 2.5])
    kinds = sorted(o.kind for o in scene.openings)
    assert kinds == ["door", "door", "window"]  # the door annotated twice is one gap; the opening is a door to the ceiling
    # Free space: the rooms (20 + 16 m2), the door through the 0.2 m wall, the opening through the 0.15 m outer wall.
    assert scene.free_space.area == pytest.approx(20 + 16 + 1.0 * 0.2 + 2.0 * 0.15, abs=0.01)


def test_segment_heights_follow_each_room(zind_file):
    m, _ = build_map(zind_file, BuildOptions(robot_radius=0.1))
    seg, kinds = m.segments, m.kinds
    x_mid = seg[:, :, 0].mean(axis=1)
    in_a, in_b = x_mid < 5.0 - 1e-6, x_mid > 5.2 + 1e-6
    ceil = kinds == SegmentKind.CEILING
    assert ceil.any()
    assert np.allclose(seg[ceil & in_a][:, :, 2], 2.5) and np.allclose(seg[ceil & in_b][:, :, 2], 2.4)
    vert = np.isin(kinds, [SegmentKind.VERTICAL, SegmentKind.JAMB])
    corners_a = vert & in_a & (np.abs(seg[:, 0, 1]) < 1e-6)  # A's corners at y = 0: floor to its ceiling
    assert corners_a.any() and np.allclose(seg[corners_a][:, :, 2].max(axis=1), 2.5)
    corners_b = vert & in_b & (np.abs(seg[:, 0, 1] - 4.0) < 1e-6)
    assert corners_b.any() and np.allclose(seg[corners_b][:, :, 2].max(axis=1), 2.4)
    assert m.meta["camera"]["height_m"] == pytest.approx(1.25)
    assert m.meta["wall_height"] == pytest.approx(2.5)


def test_door_and_opening_gaps(zind_file):
    m, _ = build_map(zind_file, BuildOptions(robot_radius=0.1))
    seg, kinds = m.segments, m.kinds
    # A's floor line on its east face x = 5 is broken by the door, y 1..2.
    east = (kinds == SegmentKind.FLOOR) & np.all(np.abs(seg[:, :, 0] - 5.0) < 1e-6, axis=1)
    spans = sorted(tuple(sorted(s[:, 1].round(3))) for s in seg[east])
    assert spans == [(0.0, 1.0), (2.0, 4.0)]
    # Its lintel at the door head, 2.0 m, across the gap.
    lintel = (kinds == SegmentKind.LINTEL) & np.all(np.abs(seg[:, :, 0] - 5.0) < 1e-6, axis=1)
    assert lintel.sum() == 1 and np.allclose(seg[lintel][0, :, 2], 2.0)
    assert sorted(seg[lintel][0, :, 1].round(3)) == [1.0, 2.0]
    # B's south face has floor edges only outside the opening x 6..8, and the opening reaches its ceiling: no lintel.
    south = np.all(np.abs(seg[:, :, 1]) < 1e-6, axis=1) & (seg[:, :, 0].min(axis=1) >= 5.2 - 1e-6)
    floor_spans = sorted(tuple(sorted(s[:, 0].round(3))) for s in seg[south & (kinds == SegmentKind.FLOOR)])
    assert floor_spans == [(5.2, 6.0), (8.0, 9.2)]
    assert not (south & (kinds == SegmentKind.LINTEL)).any()
    # The window: sill and head edges at 0.9 and 2.1 m on A's north face.
    north = np.all(np.abs(seg[:, :, 1] - 4.0) < 1e-6, axis=1) & (kinds == SegmentKind.WINDOW)
    assert sorted(set(seg[north][:, 0, 2].round(3))) == [0.9, 2.1]


def test_an_opening_annotated_from_one_side_is_a_recess(tmp_path):
    path = tmp_path / "zind_data.json"
    path.write_text(json.dumps(zind_doc(recess=True)))
    m, report = build_map(path, BuildOptions(robot_radius=0.1))
    seg, kinds = m.segments, m.kinds
    floor = kinds == SegmentKind.FLOOR

    def spans(x):
        on = floor & np.all(np.abs(seg[:, :, 0] - x) < 1e-6, axis=1)
        return sorted(tuple(sorted(s[:, 1].round(3))) for s in seg[on])

    assert spans(5.0) == [(0.0, 1.0), (2.0, 4.0)]  # A's face: only the door
    assert spans(5.2) == [(0.0, 1.0), (2.0, 3.0), (3.6, 4.0)]  # B's face: the door and the recess
    assert any("one side only" in w for w in report.warnings)


def test_cli_builds_and_the_camera_flag_wins(zind_file, tmp_path, capsys):
    code, out, err = run(capsys, "build", zind_file, "-o", tmp_path / "home.lmap", "--camera-height", "1.1")
    assert code == 0, err
    from linemap.lmap import load_map

    assert load_map(tmp_path / "home.lmap").meta["camera"]["height_m"] == pytest.approx(1.1)


def test_several_floors_first_with_warning_or_the_named_one(tmp_path, capsys, caplog):
    path = tmp_path / "zind_data.json"
    path.write_text(json.dumps(zind_doc(floors=("floor_01", "floor_02"))))
    scene = load_scene(path, BuildOptions())
    assert scene.info["floor"] == "floor_01"
    assert any("--floor-name" in w for w in scene.info["warnings"])
    assert load_scene(path, BuildOptions(floor_name="floor_02")).info["floor"] == "floor_02"
    assert_one_line_error(*run(capsys, "build", path, "-o", tmp_path / "o.lmap", "--floor-name", "floor_09"),
                          "no floor 'floor_09'", "floor_01, floor_02")


def test_malformed_zind_is_one_line(tmp_path, capsys):
    doc = zind_doc()
    del doc["merger"]["floor_01"]["complete_room_02"]["partial_room_02"]["pano_2"]["layout_complete"]["vertices"]
    doc["merger"]["floor_01"]["complete_room_02"]["partial_room_02"]["pano_2"].pop("layout_raw")
    path = tmp_path / "zind_data.json"
    path.write_text(json.dumps(doc))
    assert_one_line_error(*run(capsys, "build", path, "-o", tmp_path / "o.lmap"), "malformed ZInD", "vertices")
    doc = zind_doc()
    doc["scale_meters_per_coordinate"]["floor_01"] = None
    path.write_text(json.dumps(doc))
    assert_one_line_error(*run(capsys, "build", path, "-o", tmp_path / "o.lmap"), "no scale")
    assert not (tmp_path / "o.lmap").exists()


@pytest.mark.parametrize("content, needle", [
    ('{"rooms": [[0, 0, 1, 1]]}', "ZInD annotations"),
    ('{"rooms": [[0, 0, 1, 1]]}', "a segments file"),
    ('{"segments": [[0, 0, 1, 1]]}', "segment 1 is not six finite numbers"),
    ("[1, 2, 3]", "ZInD annotations"),
    ("{not json", "not valid JSON"),
    ("[" * 100000 + "]" * 100000, "not valid JSON"),
])
def test_other_json_is_one_line(tmp_path, capsys, content, needle):
    path = tmp_path / "plan.json"
    path.write_text(content)
    assert_one_line_error(*run(capsys, "build", path, "-o", tmp_path / "o.lmap"), needle)
