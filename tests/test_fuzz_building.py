"""Damaged buildings (the manifest's JSON mutated, a storey's map damaged
or missing): every command that reads a building ends in a one-line error
or works, within its bound."""

from __future__ import annotations

import pytest
from fuzz_helpers import CALL_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st

from mapkit_harness.fuzz.buildings import base_manifest, building_case
from mapkit_harness.fuzz.campaign import preload


@pytest.fixture(scope="module", autouse=True)
def _warm():
    preload()


@pytest.mark.slow
@fuzz_settings(examples=25)
@given(rng=st.randoms(use_true_random=False))
def test_a_damaged_building_is_refused_in_one_line_or_read(tmp_path_factory, rng):
    case = building_case(rng)
    check_case(case, tmp_path_factory.mktemp("case"), CALL_BOUND_S)


def test_the_undamaged_building_loads(tmp_path):
    """The family's starting point is a valid building: what the cases find is the damage's."""
    import json

    import matcher
    from mapkit_harness.fuzz.cases import ROOT

    (tmp_path / "building.json").write_text(json.dumps(base_manifest()))
    for s in base_manifest()["storeys"]:
        (tmp_path / s["map"]).write_bytes((ROOT / "maps" / "flat.lmap").read_bytes())
    b = matcher.load_map(tmp_path)
    assert [s.name for s in b.mapped] == ["Ground", "Upper"]


def test_a_storey_without_a_map_key_is_shown_as_having_no_map(tmp_path, capsys):
    """The manifest's shape check reads an absent 'map' as null (a storey
    built without a map); 'mapkit info' must say so, not fail on the key."""
    import json

    from mapkit.cli import main
    from mapkit_harness.fuzz.cases import ROOT

    doc = base_manifest()
    del doc["storeys"][1]["map"]
    (tmp_path / "building.json").write_text(json.dumps(doc))
    (tmp_path / doc["storeys"][0]["map"]).write_bytes((ROOT / "maps" / "flat.lmap").read_bytes())
    assert main(["info", str(tmp_path / "building.json")]) == 0
    out = capsys.readouterr().out
    [upper] = [line for line in out.splitlines() if "Upper" in line and "floor" in line]
    assert upper.endswith("no map")
