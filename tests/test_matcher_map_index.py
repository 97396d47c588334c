"""The matcher's per-map index (matcher/map_index.py): one per map, each
part kept per the constants it is built with (``Tolerances.map_index``)
and shared by tolerances that differ elsewhere."""

from __future__ import annotations

from dataclasses import fields, replace
from pathlib import Path

import pytest

import matcher
from matcher.map_index import PART_FIELDS, index_of
from matcher.map_geometry.freespace import free_space
from matcher.tolerances import DEFAULT, MapIndexConstants

MAP = Path(__file__).resolve().parents[1] / "maps" / "flat.lmap"


@pytest.fixture()
def flat():
    return matcher.load_map(MAP)  # a fresh map: nothing cached yet


class _Reads:
    """The default map index constants, noting every field read."""

    def __init__(self) -> None:
        object.__setattr__(self, "read", set())

    def __getattr__(self, name):
        self.read.add(name)
        return getattr(DEFAULT.map_index, name)


@pytest.mark.parametrize("part", sorted(PART_FIELDS))
def test_each_part_reads_only_the_fields_it_is_kept_by(flat, part):
    work = _Reads()
    built = getattr(index_of(flat), part)(work)
    assert built is not None
    assert work.read and work.read <= set(PART_FIELDS[part]), work.read - set(PART_FIELDS[part])


def test_one_index_and_one_raster_per_map_whoever_asks(flat):
    assert index_of(flat) is index_of(flat)
    fs = free_space(flat)
    # A localisation with other tolerances elsewhere uses the same raster.
    cam = matcher.Camera.from_dict({"width": 640, "height": 480, "fx": 900, "fy": 900, "cx": 320, "cy": 240,
                                    "height_m": 1.2, "pitch_deg": 0.0})
    tol = matcher.Tolerances(e_accept=1e-3)
    matcher.localize(flat, cam, [[100, 100, 300, 100], [100, 200, 300, 210], [400, 50, 410, 400]], (3.0, 3.0, 0.0),
                     0.5, 20.0, tol)
    assert index_of(flat).free(tol.map_index) is fs
    assert index_of(flat).free(DEFAULT.map_index) is fs


def test_a_part_is_built_again_for_other_values_of_its_fields(flat):
    index = index_of(flat)
    coarse = replace(DEFAULT.map_index, free_cell_m=2 * DEFAULT.map_index.free_cell_m)
    assert index.free(coarse) is not index.free()
    assert index.free(coarse).cell > index.free().cell
    # Another part's field leaves this part alone, and the other way round.
    assert index.free(replace(DEFAULT.map_index, sight_bins=360)) is index.free()
    assert index.collinear(coarse) is index.collinear()


def test_every_map_index_constant_keys_a_part():
    """A field of MapIndexConstants no part is kept by would be read by none
    (or, worse, by one whose cache ignores it)."""
    keyed = {f for fields_ in PART_FIELDS.values() for f in fields_}
    assert keyed == {f.name for f in fields(MapIndexConstants)}
