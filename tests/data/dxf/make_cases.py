"""Writes the small edge-case DXFs of this folder (run it from anywhere).

Each file isolates one thing real drawings do; tests/test_dxf_import.py
loads them. Regenerate with ``python tests/data/dxf/make_cases.py``.
"""

from __future__ import annotations

from pathlib import Path

import ezdxf

HERE = Path(__file__).resolve().parent


def _new(insunits: int):
    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = insunits
    return doc


def room_mm(path: Path, insunits: int = 4) -> None:
    """A 10 m x 8 m room drawn in millimetres, single-line walls on 'Walls'."""
    doc = _new(insunits)
    doc.layers.add("Walls")
    doc.modelspace().add_lwpolyline([(0, 0), (10000, 0), (10000, 8000), (0, 8000)], close=True, dxfattribs={"layer": "Walls"})
    doc.saveas(path)


def bulge_apse(path: Path) -> None:
    """A 6 m x 4 m room (metres) whose east wall is a half circle of radius 2 (bulge 1)."""
    doc = _new(6)
    doc.layers.add("Walls")
    # LWPOLYLINE points are (x, y, start_width, end_width, bulge); bulge 1 = half circle.
    pts = [(0, 0, 0, 0, 0), (6, 0, 0, 0, 1), (6, 4, 0, 0, 0), (0, 4, 0, 0, 0)]
    doc.modelspace().add_lwpolyline(pts, format="xyseb", close=True, dxfattribs={"layer": "Walls"})
    doc.saveas(path)


def nested_blocks(path: Path) -> None:
    """Blocks as CAD programs nest them.

    - Block LEAF (layer 0): the door leaf line (0,0)-(0,0.9) and its swing arc
      centred at (0,0), radius 0.9, from 0 to 90 degrees.
    - Block DOORSET (layer 0): LEAF inserted at (0.05, 0).
    - DOORSET inserted on layer A-DOOR at (2, 3), rotated 90 degrees and
      mirrored (xscale -1): the leaf then runs from (2, 2.95) to (1.1, 2.95)
      and the arc from (2, 2.05) to (1.1, 2.95) about (2, 2.95).
    - Block COL (layer 0): a 0.3 m square; MINSERT on A-COLS at (10, 0),
      3 columns x 2 rows, spacing 4 m x 5 m.
    - A wall line on A-WALL and a loose TEXT on A-ANNO.
    """
    doc = _new(6)
    for name in ("A-DOOR", "A-COLS", "A-WALL", "A-ANNO"):
        doc.layers.add(name)
    leaf = doc.blocks.new("LEAF")
    leaf.add_line((0, 0), (0, 0.9))
    leaf.add_arc((0, 0), 0.9, 0, 90)
    doorset = doc.blocks.new("DOORSET")
    doorset.add_blockref("LEAF", (0.05, 0))
    col = doc.blocks.new("COL")
    col.add_lwpolyline([(0, 0), (0.3, 0), (0.3, 0.3), (0, 0.3)], close=True)
    msp = doc.modelspace()
    msp.add_blockref("DOORSET", (2, 3), dxfattribs={"layer": "A-DOOR", "rotation": 90, "xscale": -1})
    cols = msp.add_blockref("COL", (10, 0), dxfattribs={"layer": "A-COLS"})
    cols.grid(size=(2, 3), spacing=(5, 4))  # rows, columns; row spacing, column spacing
    msp.add_line((0, 0), (20, 0), dxfattribs={"layer": "A-WALL"})
    msp.add_text("LIVING", dxfattribs={"layer": "A-ANNO"}).set_placement((1, 1))
    doc.saveas(path)


def unsupported(path: Path) -> None:
    """A room plus entities the importer does not read: 3DFACE x2 (reported), MTEXT (silent)."""
    doc = _new(6)
    doc.layers.add("Walls")
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (5, 0), (5, 4), (0, 4)], close=True, dxfattribs={"layer": "Walls"})
    msp.add_3dface([(1, 1, 0), (2, 1, 0), (2, 2, 0)], dxfattribs={"layer": "Walls"})
    msp.add_3dface([(3, 1, 0), (4, 1, 0), (4, 2, 0)], dxfattribs={"layer": "Walls"})
    msp.add_mtext("note", dxfattribs={"layer": "Walls"})
    doc.saveas(path)


def no_walls(path: Path) -> None:
    """Linework only on layers named like furniture and doors: nothing is a wall."""
    doc = _new(6)
    doc.layers.add("Furniture")
    doc.layers.add("Doors")
    msp = doc.modelspace()
    msp.add_line((0, 0), (1, 0), dxfattribs={"layer": "Furniture"})
    msp.add_line((0, 1), (1, 1), dxfattribs={"layer": "Doors"})
    doc.saveas(path)


def empty(path: Path) -> None:
    """A valid DXF with no entities."""
    _new(6).saveas(path)


def damaged(source: Path, path: Path) -> None:
    """``source`` without its closing EOF tag: strict readers refuse it, recovery works."""
    text = source.read_text()
    path.write_text(text.replace("\n  0\nEOF\n", "\n"))


def truncated(source: Path, path: Path) -> None:
    """The first 300 bytes of ``source``: cut inside the header, nothing to recover."""
    path.write_bytes(source.read_bytes()[:300])


def main() -> None:
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        room_mm(HERE / "room_mm.dxf")
        room_mm(HERE / "room_mm_unitless.dxf", insunits=0)
        bulge_apse(HERE / "bulge_apse.dxf")
        nested_blocks(HERE / "nested_blocks.dxf")
        unsupported(HERE / "unsupported.dxf")
        no_walls(HERE / "no_walls.dxf")
        empty(HERE / "empty.dxf")
        damaged(HERE / "room_mm.dxf", HERE / "damaged_no_eof.dxf")
        truncated(HERE / "room_mm.dxf", HERE / "truncated.dxf")
        (HERE / "not_a_dxf.dxf").write_text("name,x,y\nkitchen,1,2\n")
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = False


if __name__ == "__main__":
    main()
