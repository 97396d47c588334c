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
def test_an_entity_with_a_nan_coordinate_is_left_out_and_named(tmp_path, capsys, kind):
    path, handle = _damaged(tmp_path, kind)
    code, out, err = run(capsys, "build", path, "-o", tmp_path / "out.lmap")
    assert code == 0, err
    assert "Traceback" not in err
    assert f"non-finite coordinates, handle {handle}" in err
    assert "wrote" in out and (tmp_path / "out.lmap").exists()
