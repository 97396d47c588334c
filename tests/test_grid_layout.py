"""The one layout of the harness's grids of rooms
(mapkit_harness/plans/grid_layout.py): where its doorways stand, that its
pieces and doorways make up each wall, and that the three generators
drawing a grid (DXF, LineMap, mesh) draw that layout."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import box

from linemap.lmap import SegmentKind
from mapkit_harness.plans import RoomGridLayout, grid_flat, office_grid, room_grid


def test_doorways_stand_at_the_convention_and_hinges_alternate():
    layout = RoomGridLayout((3, 2), (4.0, 3.5), 0.12, 0.9)
    walls = layout.walls()
    assert [w.index for w in walls] == [0, 1, 2, 3, 0, 1, 2]
    for wall in walls:
        assert len(wall.doorways) == (0 if wall.outer else 2 if wall.between_columns else 3)
        size, at = (3.5, 0.5) if wall.between_columns else (4.0, 0.3)  # the convention
        for d in wall.doorways:
            assert np.mean(d.span) == pytest.approx((d.room + at) * size)
            assert d.span[1] - d.span[0] == pytest.approx(0.9)
            # The door on the west (north) face, its hinge at either jamb in turn.
            face = wall.band[0] if wall.between_columns else wall.band[1]
            along = 1 if wall.between_columns else 0
            assert d.hinge[1 - along] == d.latch[1 - along] == face
            low_hinge = (wall.index + d.room) % 2 == 1
            assert d.hinge[along] == (d.span[0] if low_hinge else d.span[1])
            assert d.swing_side == (1 if low_hinge else -1)
    assert layout.outline == (0.0, 0.0, 12.0, 7.0)
    assert layout.inside == pytest.approx((0.12, 0.12, 11.88, 6.88))


@pytest.mark.parametrize("placement, junctions", [("centred", "overlap"), ("after_line", "butt")])
def test_pieces_and_doorways_make_up_each_wall(placement, junctions):
    layout = RoomGridLayout((3, 2), (4.0, 3.0), 0.2, None if junctions == "butt" else 0.8, placement, junctions)
    walls = layout.walls()
    rows = shapely.union_all([box(*w.whole) for w in walls if not w.between_columns])
    for wall in walls:
        pieces = [box(*p) for p in wall.pieces]
        assert all(a.intersection(b).area == 0 for k, a in enumerate(pieces) for b in pieces[k + 1:])
        made = shapely.union_all(pieces + [box(*d.rect) for d in wall.doorways])
        expected = box(*wall.whole)
        if wall.between_columns and junctions == "butt":  # stops at the walls between rows
            expected = expected.difference(rows)
        assert made.symmetric_difference(expected).area < 1e-9
    if junctions == "butt":  # every wall junction two touching boxes, no overlap
        everything = [box(*p) for w in walls for p in w.pieces]
        assert shapely.union_all(everything).area == pytest.approx(sum(b.area for b in everything))
        assert layout.outline == (0.0, 0.0, 12.2, 6.2)


def test_the_generators_draw_the_layout(tmp_path):
    layout = RoomGridLayout((2, 2), (4.0, 4.0), 0.15, 0.9)
    facts = office_grid(tmp_path / "office.dxf", n=2, room=4.0)
    doorways = [box(*d.rect) for w in layout.walls() for d in w.doorways]
    assert facts.doors == len(doorways) == 4
    assert all(a.equals(b) for a, b in zip(facts.extra["door_gaps"], doorways, strict=True))
    assert facts.walls.equals(shapely.union_all([box(*p) for w in layout.walls() for p in w.pieces]))

    flat = grid_flat(rooms=(2, 2), room_size=(4.0, 4.0), wall_thickness=0.15)
    lintel_ends = {tuple(np.round(p[:2], 6)) for s in flat.segments[flat.kinds == SegmentKind.LINTEL] for p in s}
    corners = {tuple(np.round(c, 6)) for d in doorways for c in shapely.get_coordinates(d)}
    assert lintel_ends == corners

    mesh = room_grid(2, 0)
    walls = RoomGridLayout((2, 2), (4.0, 3.0), 0.2, placement="after_line", junctions="butt").walls()
    assert mesh.volume == pytest.approx(2.5 * sum((p[2] - p[0]) * (p[3] - p[1]) for w in walls for p in w.pieces))
