"""Damaged drawings: an entity with a NaN coordinate is left out with a
warning that names it, and the rest of the plan builds as fast as without
it (a NaN door insert used to stall the build for minutes, a NaN wall line
to end in a GEOS traceback)."""

from __future__ import annotations

from pathlib import Path

import ezdxf
import pytest
from cli_helpers import run

ROOT = Path(__file__).resolve().parent.parent
FLAT = ROOT / "maps" / "flat.dxf"


def _damaged(tmp_path, kind: str) -> tuple[Path, str]:
    doc = ezdxf.readfile(FLAT)
    msp = doc.modelspace()
    if kind == "door insert":
        e = next(e for e in msp if e.dxftype() == "INSERT" and e.dxf.layer == "A-DOOR")
        e.dxf.insert = (float("nan"), e.dxf.insert.y, 0.0)
    else:
        e = next(e for e in msp if e.dxftype() == "LINE" and e.dxf.layer == "A-WALL")
        e.dxf.start = (float("nan"), 1.0, 0.0)
    path = tmp_path / f"{kind.replace(' ', '_')}.dxf"
    doc.saveas(path)
    return path, e.dxf.handle


@pytest.mark.parametrize("kind", ["door insert", "wall line"])
@pytest.mark.slow
def test_an_entity_with_a_nan_coordinate_is_left_out_and_named(tmp_path, capsys, kind):
    path, handle = _damaged(tmp_path, kind)
    code, out, err = run(capsys, "build", path, "-o", tmp_path / "out.lmap")
    assert code == 0, err
    assert "Traceback" not in err
    assert f"non-finite coordinates, handle {handle}" in err
    assert "wrote" in out and (tmp_path / "out.lmap").exists()


def test_an_entity_far_outside_the_rest_is_left_out_and_named(tmp_path, capsys):
    """A wall line whose end reads 1e9 (a damaged number) made the plan a
    million kilometres across, refused as a unit error; it is left out
    instead, named, and the rest of the plan is read."""
    doc = ezdxf.readfile(FLAT)
    e = next(e for e in doc.modelspace() if e.dxftype() == "LINE" and e.dxf.layer == "A-WALL")
    e.dxf.end = (1e9, e.dxf.end.y, 0.0)
    path = tmp_path / "wild.dxf"
    doc.saveas(path)
    code, out, err = run(capsys, "preview", path, "-o", tmp_path / "p.png")
    assert code == 0, err
    assert f"far outside the rest of the drawing, handle {e.dxf.handle} on layer A-WALL" in err
    assert "Traceback" not in err and (tmp_path / "p.png").exists()
