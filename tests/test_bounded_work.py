"""Bounded work: inputs that used to run for minutes or take gigabytes end
in a clear error naming the limit and the option that raises it, or leave
the offending entity out with a warning; sizes the limits allow stay within
a bounded memory."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from cli_helpers import run

ROOT = Path(__file__).resolve().parent.parent
FLAT = ROOT / "maps" / "flat.dxf"


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


def test_the_free_space_raster_of_a_2_km_map_stays_small():
    """A plan 2 km across (the builder's limit) would need a raster of 1.6e9
    cells at 5 cm: the cells grow instead, and the distances stay right."""
    from matcher.scene.freespace import FreeSpace
    from matcher.tolerances import DEFAULT_INTERNALS

    ring = np.array([[0.0, 0.0], [2000.0, 0.0], [2000.0, 2000.0], [0.0, 2000.0]])
    fs = FreeSpace(ring, np.array([0, 4]))
    assert fs.dist.size <= DEFAULT_INTERNALS.free_max_cells
    assert fs.distance(np.array([[1000.0, 1000.0], [5.0, 5.0]])).tolist() == [0.0, 0.0]
    assert 0.0 < fs.distance(np.array([[1000.0, -0.9]]))[0] <= 0.9 + fs.cell
