"""Maps from 3D segments one already has (mapkit/importers/segments.py):
JSON with an outline, CSV alone, kinds given or read from the geometry."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run
from linemap.lmap import KIND_NAMES
from mapkit import load_map
from mapkit.importers import load_scene

ROOT = Path(__file__).resolve().parents[1]


def _box(w: float, d: float, h: float) -> list[list[float]]:
    """A w x d room h high: 4 floor, 4 ceiling and 4 vertical segments."""
    c = [(0.0, 0.0), (w, 0.0), (w, d), (0.0, d)]
    rows = []
    for z in (0.0, h):
        rows += [[*c[i], z, *c[(i + 1) % 4], z] for i in range(4)]
    rows += [[x, y, 0.0, x, y, h] for x, y in c]
    return rows


def test_a_json_room_with_an_outline_builds_with_kinds_read_from_the_geometry(tmp_path, capsys):
    src = tmp_path / "room.json"
    src.write_text(json.dumps({"segments": _box(4.0, 3.0, 2.5), "outline": [[0, 0], [4, 0], [4, 3], [0, 3]]}))
    scene = load_scene(src)
    kinds = [KIND_NAMES[k] for k in scene.kinds]
    assert kinds.count("floor") == 4 and kinds.count("ceiling") == 4 and kinds.count("vertical") == 4
    assert scene.wall_height == pytest.approx(2.5)
    # The outline less the robot's 0.2 m: 3.6 x 2.6 m.
    assert scene.free_space.area == pytest.approx(3.6 * 2.6, rel=0.02)
    code, out, err = run(capsys, "build", src, "-o", tmp_path / "room.lmap", "-q")
    assert code == 0, err
    assert load_map(tmp_path / "room.lmap").n_segments == 12


@pytest.mark.slow
def test_a_csv_of_the_example_map_finds_its_rooms_without_an_outline(tmp_path, capsys):
    """The example map's segments with their kinds, as a CSV with a header:
    the rooms the floor-level segments enclose are the free space."""
    m = load_map(ROOT / "maps" / "flat.lmap")
    src = tmp_path / "flat.csv"
    with open(src, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x1", "y1", "z1", "x2", "y2", "z2", "kind"])
        for seg, kind in zip(m.segments, m.kinds):
            w.writerow([*seg.ravel().round(4).tolist(), KIND_NAMES[kind]])
    scene = load_scene(src)
    assert len(scene.segments) == m.n_segments
    assert (scene.kinds == m.kinds).all()
    # Seven rooms of the flat (its corridor opens wider than a door), each
    # less the robot's radius; nothing outside the building.
    parts = list(scene.free_space.geoms)
    assert 6 <= len(parts) <= 8
    assert 45.0 < scene.free_space.area < 62.0
    lo, hi = m.ring_points.min(axis=0), m.ring_points.max(axis=0)
    fx0, fy0, fx1, fy1 = scene.free_space.bounds
    assert fx0 >= lo[0] - 0.1 and fy0 >= lo[1] - 0.1 and fx1 <= hi[0] + 0.1 and fy1 <= hi[1] + 0.1
    code, out, err = run(capsys, "build", src, "-o", tmp_path / "flat.lmap", "-q")
    assert code == 0, err
    assert load_map(tmp_path / "flat.lmap").n_segments > 0.6 * m.n_segments


@pytest.mark.parametrize("rows, needle", [
    ([[0, 0, 0, 1, 0]], "segment 1 is not six finite numbers"),
    ([[0, 0, 0, 1, 0, 0], [0, 0, 0, 1, "x", 0]], "segment 2 is not six finite numbers"),
    ([[0, 0, 0, 1, 0, 0, "wall"]], "has kind 'wall'"),
    ([[0, 0, 0, float("nan"), 0, 0]], "segment 1 is not six finite numbers"),
])
def test_bad_segment_rows_are_one_line_errors(tmp_path, capsys, rows, needle):
    src = tmp_path / "bad.csv"
    with open(src, "w", newline="") as f:
        csv.writer(f).writerows(rows)
    code, out, err = run(capsys, "build", src, "-o", tmp_path / "bad.lmap")
    assert_one_line_error(code, out, err, needle)
    assert not (tmp_path / "bad.lmap").exists()


def test_segments_that_enclose_nothing_ask_for_an_outline(tmp_path, capsys):
    src = tmp_path / "open.csv"
    src.write_text("0,0,0,5,0,0\n0,0,0,0,0,2.5\n")
    code, out, err = run(capsys, "build", src, "-o", tmp_path / "open.lmap")
    assert_one_line_error(code, out, err, "outline")


def test_segment_kinds_are_read_from_heights():
    from mapkit.importers.segments import _infer_kinds

    segs = np.array(_box(2.0, 2.0, 2.5) + [[0.5, 0.0, 1.0, 1.5, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0, 0.0, 1.0]],
                    dtype=float).reshape(-1, 2, 3)
    names = [KIND_NAMES[k] for k in _infer_kinds(segs)]
    assert names[-2:] == ["horizontal", "oblique"]
