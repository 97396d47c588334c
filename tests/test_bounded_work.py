"""Bounded work: inputs that used to run for minutes or take gigabytes end
in a clear error naming the limit and the option that raises it, or leave
the offending entity out with a warning; sizes the limits allow stay within
a bounded memory."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_helpers import run

ROOT = Path(__file__).resolve().parent.parent
FLAT = ROOT / "maps" / "flat.dxf"


@pytest.mark.slow
def test_a_bulge_larger_than_any_building_is_left_out_with_a_warning(tmp_path, capsys):
    """One byte of maps/flat.dxf changed ('0.414...' to '0041...'): a bed's
    bulge of 4.14e16 used to take over 7 GB to flatten; the furniture
    insert is now left out, named, and the rest builds as before."""
    text = FLAT.read_text()
    bad = text.replace("\n0.41421356237309503\n", "\n0041421356237309503\n", 1)
    assert len(bad) == len(text) and bad != text
    plan = tmp_path / "bulge.dxf"
    plan.write_text(bad)
    code, out, err = run(capsys, "build", plan, "-o", tmp_path / "out.lmap")
    assert code == 0, err
    assert "larger than 2000 m, handle 132 on layer A-FURN" in err
    assert "264 segments, 104 regions" in out


@pytest.mark.slow
def test_the_free_space_raster_of_a_2_km_map_stays_small():
    """A plan 2 km across (the builder's limit) would need a raster of 1.6e9
    cells at 5 cm: the cells grow instead, and the distances stay right."""
    from matcher.map_geometry.freespace import FreeSpace
    from matcher.tolerances import DEFAULT

    ring = np.array([[0.0, 0.0], [2000.0, 0.0], [2000.0, 2000.0], [0.0, 2000.0]])
    fs = FreeSpace(ring, np.array([0, 4]))
    assert fs.dist.size <= DEFAULT.map_index.free_max_cells
    assert fs.distance(np.array([[1000.0, 1000.0], [5.0, 5.0]])).tolist() == [0.0, 0.0]
    assert 0.0 < fs.distance(np.array([[1000.0, -0.9]]))[0] <= 0.9 + fs.cell


def test_a_matcher_call_has_a_time_budget_by_default():
    """Hundreds of look-alike lines used to keep the tree busy for minutes
    (tests/data/fuzz/lines_450_lookalikes): a call without a budget given
    still ends, with a reason naming the budget."""
    import math

    import matcher

    assert math.isfinite(matcher.Tolerances().time_budget_ms)


def test_line_pieces_in_blocks_is_the_whole_pass(monkeypatch):
    """Line preparation compares every pair of lines a block of rows at a
    time (bounded memory however many lines): the same pairs as all at once."""
    import matcher
    from matcher.search.tree import constraints

    rng = np.random.default_rng(5)
    cam = matcher.Camera.from_dict({"width": 640, "height": 480, "fx": 500.0, "fy": 500.0, "cx": 320.0,
                                    "cy": 240.0, "height_m": 1.2, "pitch_deg": 0.0})
    a = rng.uniform([0, 0], [640, 480], (300, 2))
    lines = np.stack([a, a + rng.normal(0, 60, (300, 2))], axis=1)
    lines[100:200] = lines[0] + (lines[0, 1] - lines[0, 0]) * rng.uniform(1.1, 3, (100, 1, 1))  # one line's pieces
    normals = cam.interpretation_normals(lines)
    eps, _, _ = constraints.plane_noises(cam, lines, 1.0, 1.0)
    whole = constraints.line_pieces(lines, normals, eps, 6.0)
    monkeypatch.setattr(constraints, "_PAIR_BLOCK", 1000)
    blocked = constraints.line_pieces(lines, normals, eps, 6.0)
    assert whole.sum() > 100 and (blocked == whole).all()


def test_more_lines_than_the_limit_name_the_option(tmp_path, capsys):
    import json

    from matcher.cli import main

    rng = np.random.default_rng(2)
    a = rng.uniform([10, 10], [600, 440], (2500, 2))
    lines = np.concatenate([a, a + 20.0], axis=1).round(2).tolist()
    (tmp_path / "lines.json").write_text(json.dumps({"lines": lines}))
    (tmp_path / "cam.json").write_text(json.dumps({"width": 640, "height": 480, "fx": 500.0, "fy": 500.0, "cx": 320.0,
                                                    "cy": 240.0, "height_m": 1.2, "pitch_deg": 0.0}))
    argv = ["localize", "--map", str(ROOT / "maps" / "flat.lmap"), "--camera", str(tmp_path / "cam.json"),
            "--lines", str(tmp_path / "lines.json"), "--prior", "5,5,0", "--dt", "0.3", "--dyaw", "10"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "2500 image lines" in err and "--max-lines" in err and len(err.splitlines()) == 1
    assert main(argv + ["--max-lines", "3000", "--budget-ms", "200"]) in (0, 1)
    assert "not localised" in capsys.readouterr().out


def _room(path, side: float, copies: tuple[int, int] | None = None, lines: int = 0) -> None:
    """A square room ``side`` metres across on A-WALL; optionally a column
    block inserted as a MINSERT array of ``copies`` (rows, columns) and
    ``lines`` short wall LINEs."""
    import ezdxf

    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    doc.layers.add("A-WALL")
    msp.add_lwpolyline([(0, 0), (side, 0), (side, side), (0, side)], close=True, dxfattribs={"layer": "A-WALL"})
    if copies:
        block = doc.blocks.new("COLUMN")
        block.add_lwpolyline([(0, 0), (0.3, 0), (0.3, 0.3), (0, 0.3)], close=True)
        ins = msp.add_blockref("COLUMN", (1, 1), dxfattribs={"layer": "A-WALL"})
        ins.grid(size=copies, spacing=(0.5, 0.5))
    for i in range(lines):
        msp.add_line((1 + 0.1 * (i % 100), 1 + 0.1 * (i // 100)), (1.05 + 0.1 * (i % 100), 1 + 0.1 * (i // 100)),
                     dxfattribs={"layer": "A-WALL"})
    doc.saveas(path)


def _one_line_error(code, out, err, *needles):
    lines = [ln for ln in err.splitlines() if not ln.startswith("mapkit: warning:")]
    assert code == 2 and out == "" and len(lines) == 1 and lines[0].startswith("mapkit: error: "), (code, err)
    for n in needles:
        assert n in lines[0], lines[0]


@pytest.mark.slow
def test_a_room_2_km_across_is_refused_before_the_region_builder(tmp_path, capsys):
    """An empty square room 1999 m across (inside the 2 km plan limit) ran
    out of memory; it is now refused in seconds, naming the option."""
    _room(tmp_path / "huge.dxf", 1999.0)
    code, out, err = run(capsys, "build", tmp_path / "huge.dxf", "-o", tmp_path / "huge.lmap")
    # Its walls are 0.02 % of its floor, which no building has: the self-check refuses it first.
    _one_line_error(code, out, err, "contradicts its drawing", "--accept-inconsistent")
    # Written anyway when asked, the floor bound still refuses it before the region builder.
    code, out, err = run(capsys, "build", tmp_path / "huge.dxf", "-o", tmp_path / "huge.lmap", "--accept-inconsistent")
    _one_line_error(code, out, err, "1998 x 1998 m", "--max-floor-area")
    assert not (tmp_path / "huge.lmap").exists()


def test_the_floor_limit_is_an_option(tmp_path, capsys):
    _room(tmp_path / "room.dxf", 20.0)
    code, out, err = run(capsys, "build", tmp_path / "room.dxf", "-o", tmp_path / "a.lmap", "--max-floor-area", "100")
    _one_line_error(code, out, err, "--max-floor-area")
    code, out, err = run(capsys, "build", tmp_path / "room.dxf", "-o", tmp_path / "a.lmap")
    assert code == 0, err


def test_a_million_block_copies_are_refused_without_expanding_them(tmp_path, capsys):
    """A MINSERT of 1000 x 1000 columns ran for minutes (its bounding box
    alone expanded every copy); counted from the block, it is refused at once."""
    _room(tmp_path / "minsert.dxf", 30.0, copies=(1000, 1000))
    code, out, err = run(capsys, "build", tmp_path / "minsert.dxf", "-o", tmp_path / "m.lmap")
    _one_line_error(code, out, err, "more than 100000 entities", "--max-entities")


@pytest.mark.slow
def test_the_entity_limit_counts_plain_entities_and_is_an_option(tmp_path, capsys):
    _room(tmp_path / "lines.dxf", 30.0, lines=600)
    code, out, err = run(capsys, "preview", tmp_path / "lines.dxf", "-o", tmp_path / "p.png", "--max-entities", "500")
    _one_line_error(code, out, err, "more than 500 entities", "--max-entities")
    code, out, err = run(capsys, "layers", tmp_path / "lines.dxf")
    assert code == 0
