"""The bundled example plan maps/flat.dxf and its generator tools/make_flat.py.

The plan is the importer's reference drawing, so these tests pin down what
the importer may rely on: millimetre units, the layer names, the doors and
windows sitting in jamb-closed wall gaps, wall linework that closes into thin
wall pieces, and exactly the two deliberate faults (one duplicated wall line,
one 5 mm gap).
"""

from __future__ import annotations

import importlib.util
import math
from collections import Counter
from pathlib import Path

import ezdxf
import pytest
from shapely.geometry import LineString
from shapely.ops import linemerge, polygonize, polygonize_full, unary_union

ROOT = Path(__file__).resolve().parent.parent
PLAN = ROOT / "maps" / "flat.dxf"
SCRIPT = ROOT / "tools" / "make_flat.py"

WALL_THICKNESSES = (100.0, 120.0, 300.0)  # mm
EXACT = 1e-6  # mm; the generator writes shared endpoints identically


def _load_script():
    spec = importlib.util.spec_from_file_location("make_flat", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def doc():
    return ezdxf.readfile(PLAN)


@pytest.fixture(scope="module")
def wall_lines(doc):
    """A-WALL lines as ((x1, y1), (x2, y2)) tuples in mm, as drawn."""
    return [
        ((e.dxf.start.x, e.dxf.start.y), (e.dxf.end.x, e.dxf.end.y))
        for e in doc.modelspace().query('LINE[layer=="A-WALL"]')
    ]


def _signature(doc):
    """What the plan is, independent of handles and header metadata."""
    msp = doc.modelspace()
    counts = Counter((e.dxf.layer, e.dxftype()) for e in msp)
    walls = sorted(
        tuple(round(v, 3) for v in (*e.dxf.start.vec2, *e.dxf.end.vec2))
        for e in msp.query('LINE[layer=="A-WALL"]')
    )
    inserts = sorted(
        (e.dxf.name, e.dxf.layer, *(round(v, 3) for v in e.dxf.insert.vec2),
         round(e.dxf.rotation, 6), e.dxf.xscale)
        for e in msp.query("INSERT")
    )
    blocks = sorted(
        (b.name, tuple(sorted(Counter(e.dxftype() for e in b).items())))
        for b in doc.blocks
        if not b.name.startswith("*")
    )
    header = {k: doc.header[k] for k in ("$INSUNITS", "$MEASUREMENT")}
    return counts, walls, inserts, blocks, header


def test_committed_plan_is_what_the_script_draws(doc, tmp_path):
    out = tmp_path / "flat.dxf"
    assert _load_script().main(["--out", str(out)]) == 0
    assert _signature(ezdxf.readfile(out)) == _signature(doc)


def test_script_output_is_reproducible(tmp_path):
    script = _load_script()
    first, second = tmp_path / "a.dxf", tmp_path / "b.dxf"
    script.main(["--out", str(first)])
    script.main(["--out", str(second)])
    assert first.read_bytes() == second.read_bytes()
    assert not ezdxf.options.write_fixed_meta_data_for_testing  # restored


def test_plan_is_small():
    assert PLAN.stat().st_size < 200 * 1024


def test_units_are_millimetres(doc):
    assert doc.header["$INSUNITS"] == 4
    assert doc.header["$MEASUREMENT"] == 1
    assert doc.units == ezdxf.units.MM
    xmin, ymin, _ = doc.header["$EXTMIN"]
    xmax, ymax, _ = doc.header["$EXTMAX"]
    assert 10_000 < xmax - xmin < 15_000  # an ~11 m flat plus dimensions
    assert 8_000 < ymax - ymin < 13_000


def test_layers_present_and_used(doc):
    msp = doc.modelspace()
    for name in ("A-WALL", "A-DOOR", "A-GLAZ", "A-COLS", "A-FURN", "A-ANNO"):
        assert doc.layers.has_entry(name)
        assert len(msp.query(f'*[layer=="{name}"]')) > 0, name
    kinds = Counter(e.dxftype() for e in msp.query('*[layer=="A-WALL"]'))
    assert set(kinds) == {"LINE"}
    assert len(msp.query('INSERT[layer=="A-FURN"]')) >= 8
    assert Counter(e.dxftype() for e in msp.query('*[layer=="A-ANNO"]')).keys() >= {
        "TEXT", "MTEXT", "DIMENSION"}


def test_columns(doc):
    cols = Counter(e.dxftype() for e in doc.modelspace().query('*[layer=="A-COLS"]'))
    assert cols == {"LWPOLYLINE": 2, "HATCH": 2, "CIRCLE": 1}
    for hatch in doc.modelspace().query("HATCH"):
        assert hatch.dxf.solid_fill == 1


def test_door_inserts(doc):
    doors = doc.modelspace().query('INSERT[layer=="A-DOOR"]')
    assert len(doors) == 7
    assert Counter(d.dxf.name for d in doors) == {"DOOR_800": 5, "DOOR_900": 2}
    assert any(d.dxf.xscale < 0 for d in doors)  # mirrored: hinges both sides
    assert any(d.dxf.xscale > 0 for d in doors)
    for name in ("DOOR_800", "DOOR_900"):
        kinds = Counter(e.dxftype() for e in doc.blocks[name])
        assert kinds == {"LWPOLYLINE": 1, "ARC": 1}
        assert all(e.dxf.layer == "0" for e in doc.blocks[name])


def _gap_of(insert, width):
    """World points of the block's local (0, 0) and (width, 0)."""
    m = insert.matrix44()
    p0, p1 = m.transform((0, 0, 0)), m.transform((width, 0, 0))
    return (p0.x, p0.y), (p1.x, p1.y)


def _jamb_at(point, along, wall_lines):
    """Length of the wall line starting at ``point`` across the gap, or None."""
    for a, b in wall_lines:
        for p, q in ((a, b), (b, a)):
            if math.dist(p, point) < EXACT:
                d = (q[0] - p[0], q[1] - p[1])
                length = math.hypot(*d)
                if abs(d[0] * along[0] + d[1] * along[1]) < EXACT * length:
                    return length
    return None


def _assert_in_gap(insert, width, wall_lines, thicknesses):
    p0, p1 = _gap_of(insert, width)
    assert math.dist(p0, p1) == pytest.approx(width)
    along = ((p1[0] - p0[0]) / width, (p1[1] - p0[1]) / width)
    for end in (p0, p1):
        jamb = _jamb_at(end, along, wall_lines)
        assert jamb is not None, f"{insert.dxf.name} at {end}: no jamb line"
        assert any(jamb == pytest.approx(t) for t in thicknesses), jamb
    # nothing of the wall lies across the opening itself
    inner = LineString([p0, p1]).interpolate(0.5, normalized=True).buffer(width / 2 - 1)
    assert not any(LineString(line).intersects(inner) for line in wall_lines)


def test_each_door_sits_in_a_wall_gap_of_its_width(doc, wall_lines):
    for door in doc.modelspace().query('INSERT[layer=="A-DOOR"]'):
        width = float(door.dxf.name.split("_")[1])
        _assert_in_gap(door, width, wall_lines, WALL_THICKNESSES)


def test_each_window_sits_in_an_exterior_wall_gap(doc, wall_lines):
    windows = doc.modelspace().query('INSERT[layer=="A-GLAZ"]')
    assert len(windows) >= 5
    for window in windows:
        width = float(window.dxf.name.split("_")[1])
        _assert_in_gap(window, width, wall_lines, (300.0,))


def test_entrance_door_is_in_the_exterior_wall(doc, wall_lines):
    widths = []
    for door in doc.modelspace().query('INSERT[layer=="A-DOOR"]'):
        width = float(door.dxf.name.split("_")[1])
        p0, p1 = _gap_of(door, width)
        along = ((p1[0] - p0[0]) / width, (p1[1] - p0[1]) / width)
        widths.append(_jamb_at(p0, along, wall_lines))
    assert widths.count(pytest.approx(300.0)) == 1


def _snap(lines, tol):
    """Move endpoints within ``tol`` of an earlier endpoint onto it."""
    kept = []
    out = []
    for line in lines:
        snapped = []
        for p in line:
            q = next((k for k in kept if math.dist(k, p) <= tol), None)
            if q is None:
                kept.append(p)
                q = p
            snapped.append(q)
        out.append(tuple(snapped))
    return out


def test_wall_faces_close_into_thin_wall_pieces_once_the_gap_is_snapped(wall_lines):
    noded = unary_union([LineString(line) for line in _snap(wall_lines, 20.0)])
    pieces = list(polygonize([noded]))
    assert len(pieces) >= 6
    for piece in pieces:
        width = 2 * piece.area / piece.length  # thin: about one wall thick
        assert width < 300.0, piece.wkt
    # every wall line bounds a piece: nothing dangles or is left over
    outline = unary_union([p.boundary for p in pieces])
    assert outline.buffer(EXACT).contains(noded)

    # as drawn, exactly one piece stays open, at the 5 mm gap
    raw = unary_union([LineString(line) for line in wall_lines])
    closed, dangles, cuts, invalid = polygonize_full([raw])
    assert len(closed.geoms) == len(pieces) - 1
    assert not invalid.geoms
    chain = linemerge([*dangles.geoms, *cuts.geoms])
    assert chain.geom_type == "LineString"
    assert math.dist(chain.coords[0], chain.coords[-1]) == pytest.approx(5.0)


def test_deliberate_dirt_is_exactly_one_duplicate_and_one_5mm_gap(wall_lines):
    keys = Counter(tuple(sorted(line)) for line in wall_lines)
    assert sorted(keys.values())[-2:] == [1, 2]  # one line twice, no other

    ends = Counter(p for line in set(keys) for p in line)
    loose = [p for p, n in ends.items() if n == 1]  # every corner joins 2+
    assert len(loose) == 2
    assert math.dist(*loose) == pytest.approx(5.0)

