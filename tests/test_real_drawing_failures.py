"""Failures that real drawings made by strangers showed
(``tools/bench_drawings.py`` on the corpus of docs/benchmarks/drawings.md),
each reproduced in a small drawing these tests write."""

from __future__ import annotations

import ezdxf
import shapely
from cli_helpers import run
from shapely import wkt

from mapkit.importers.dxf.openings import _clipped


def _room(path, layer: str = "A-WALL", version: str = "R2013"):
    """A 5 x 4 m room of double-line walls 0.2 m thick on ``layer``."""
    doc = ezdxf.new(version)
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (5, 0), (5, 4), (0, 4)], close=True, dxfattribs={"layer": layer})
    msp.add_lwpolyline([(0.2, 0.2), (4.8, 0.2), (4.8, 3.8), (0.2, 3.8)], close=True, dxfattribs={"layer": layer})
    doc.saveas(path)
    return path


def test_a_model_space_layout_of_another_name_is_read(tmp_path, capsys):
    """An AutoCAD 2013 file written by other software names its model-space
    layout 'Default' (depthmapX's gallery.dxf); ezdxf's modelspace() then
    raised KeyError: 'MODEL', a traceback. Its *Model_Space block holds the
    drawing."""
    plain = _room(tmp_path / "plain.dxf")
    renamed = tmp_path / "renamed.dxf"
    renamed.write_text(plain.read_text().replace("\nModel\n", "\nDefault\n"))
    assert "\nModel\n" not in renamed.read_text()
    code, out, err = run(capsys, "build", renamed, "-o", tmp_path / "out.lmap")
    assert code == 0, err
    assert "Traceback" not in err and (tmp_path / "out.lmap").exists()


def test_a_wall_sliver_that_geos_rectangle_clip_refuses_is_clipped():
    """Single-line walls on one layer per room (JuPedSim's shopping mall)
    left a spike-shaped wall part on which GEOS's rectangle clip raised
    'Invalid number of points in LinearRing found 3' from inside the door
    search; the general intersection gives the same cut."""
    sliver = wkt.loads(
        "POLYGON ((400 703.4999999999999, 405.48584809268175 703.508050435386, 405.48584809268186 716.9691585455412, "
        "405.48584809268186 703.508050435386, 405.48584809268186 701.37597759, 405.48584809268175 703.5080504353859, "
        "400 703.4999999999999))")
    box = (392.84082582051, 716.9203400091477, 417.94156838924243, 750.2255208832047)
    cut = _clipped(sliver, box)
    assert cut.area == shapely.box(*box).intersection(sliver).area
