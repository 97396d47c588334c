"""Damaged meshes of every format (OBJ, OFF, ASCII and binary PLY and STL,
GLB): ``mapkit build`` ends in a one-line error or a map, within its
bound; never a traceback or a hang."""

from __future__ import annotations

import pytest
from fuzz_helpers import BUILD_BOUND_S, check_case, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st

from mapkit_harness.fuzz.campaign import preload
from mapkit_harness.fuzz.meshes import mesh_case, mesh_sources


@pytest.fixture(scope="module", autouse=True)
def _warm():
    preload()


@fuzz_settings(examples=6)
@given(rng=st.randoms(use_true_random=False))
@pytest.mark.slow
def test_a_damaged_mesh_ends_in_a_clean_error_or_a_map(tmp_path_factory, rng):
    case = mesh_case(rng)
    check_case(case, tmp_path_factory.mktemp("case"), BUILD_BOUND_S)


def test_every_format_is_fuzzed():
    names = mesh_sources()
    assert {n.rsplit(".", 1)[1] for n in names} >= {"obj", "off", "ply", "stl", "glb"}
    assert any("binary" in n for n in names if n.endswith(".ply"))
    assert any("ascii" in n for n in names if n.endswith(".stl"))
