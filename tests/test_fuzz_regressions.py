"""Every input the fuzz campaign found failing (tests/data/fuzz/*/) ends as
its case.json now expects: a one-line error naming the problem, within the
bound, where it was a traceback, a hang or a blow-up."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from fuzz_helpers import BUILD_BOUND_S

from mapkit_harness.fuzz.cases import ROOT, load_case
from mapkit_harness.fuzz.run import run_bounded

CASES = sorted(p for p in (Path(__file__).parent / "data" / "fuzz").iterdir() if (p / "case.json").is_file())


# The cases that build a map of a damaged plan or mesh take seconds each: the full run's, not the quick lane's.
SLOW_CASES = {"dxf_polyline_vertex_without_location", "mesh_section_topology_conflict", "mesh_tangled_walls_slow_regions"}


@pytest.mark.parametrize("folder", [pytest.param(p, marks=pytest.mark.slow) if p.name in SLOW_CASES else p
                                    for p in CASES], ids=[p.name for p in CASES])
def test_a_found_failure_stays_fixed(tmp_path, folder):
    expect = json.loads((folder / "case.json").read_text())
    out = run_bounded(load_case(folder), tmp_path, BUILD_BOUND_S)
    assert out.kind == expect["expect"], (out.kind, out.detail)
    assert expect["contains"].lower() in out.detail.lower(), out.detail
    assert "\n" not in out.detail.strip()


@pytest.mark.slow
def test_a_value_read_as_an_entity_type_is_left_out_with_a_warning(tmp_path, capsys):
    """The issue's case: a door INSERT's group code 10 damaged into 0, so
    its x value '10700.0' reads as an entity type (ezdxf keeps it as raw
    tags without a layer); it ended in DXFAttributeError. Now the stray
    'entity' is left out, named, and the plan builds."""
    from cli_helpers import run

    text = (ROOT / "maps" / "flat.dxf").read_text()
    marker = "DOOR_900\n 10\n10700.0\n"
    assert marker in text
    plan = tmp_path / "plan.dxf"
    plan.write_text(text.replace(marker, "DOOR_900\n  0\n10700.0\n", 1))
    code, out, err = run(capsys, "build", plan, "-o", tmp_path / "out.lmap")
    assert code == 0, err
    assert "'10700.0'" in err and "left out 1 entities of no known type" in err
    assert "Traceback" not in err and "wrote" in out
